// Quaternion helpers shared by the skeleton: shortest-path slerp (thesis eq. 4.44-4.45),
// swing-twist decomposition, yaw (heading) about the earth's up axis, angles in degrees.
// All functions are pure, allocation-free and deterministic.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include "mocap/core/units.hpp"

namespace mocap {

/// Angle of the rotation q, radians in [0, pi] (q and -q give the same angle).
inline double rotation_angle_rad(const Eigen::Quaterniond& q) {
  const double v = q.vec().norm();
  return 2.0 * std::atan2(v, std::abs(q.w()));
}

/// Angle between two orientations, degrees in [0, 180].
inline double angle_between_deg(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return rotation_angle_rad(a.conjugate() * b) * kDegPerRad;
}

/// Spherical linear interpolation along the shorter arc: t = 0 gives a, t = 1 gives b (or -b).
/// Falls back to normalised linear interpolation when the two are nearly equal.
inline Eigen::Quaterniond slerp_shortest(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b,
                                         double t) {
  double d = a.coeffs().dot(b.coeffs());
  Eigen::Vector4d bc = b.coeffs();
  if (d < 0) {
    d = -d;
    bc = -bc;
  }
  double wa, wb;
  if (d > 0.9995) {
    wa = 1.0 - t;
    wb = t;
  } else {
    const double theta = std::acos(d);
    const double s = std::sin(theta);
    wa = std::sin((1.0 - t) * theta) / s;
    wb = std::sin(t * theta) / s;
  }
  Eigen::Quaterniond r;
  r.coeffs() = wa * a.coeffs() + wb * bc;
  r.normalize();
  return r;
}

/// Rotation about a coordinate axis (0 = x, 1 = y, 2 = z) by angle_rad.
inline Eigen::Quaterniond axis_rotation(int axis, double angle_rad) {
  Eigen::Quaterniond q(std::cos(0.5 * angle_rad), 0, 0, 0);
  q.vec()[axis] = std::sin(0.5 * angle_rad);
  return q;
}

/// Heading rotation about the earth's z axis.
inline Eigen::Quaterniond yaw_rotation(double yaw_rad) {
  return axis_rotation(2, yaw_rad);
}

/// Earth yaw of a direction (the angle of its horizontal part from +x toward +y), radians in
/// (-pi, pi]; 0 for a vertical one. The one heading formula of the body side: segment facings,
/// body headings and every heading turn are measured with it.
inline double heading_of_rad(const Eigen::Vector3d& v) {
  return std::atan2(v.y(), v.x());
}

/// An angle wrapped to [-pi, pi].
inline double wrap_angle_rad(double a) {
  return std::remainder(a, 2 * M_PI);
}

/// Twist of q about the z axis (the "yaw" part in the swing-twist sense), radians in (-pi, pi].
inline double yaw_of_rad(const Eigen::Quaterniond& q) {
  double a = 2.0 * std::atan2(q.z(), q.w());
  if (a > M_PI) a -= 2 * M_PI;
  if (a <= -M_PI) a += 2 * M_PI;
  return a;
}

/// q = swing * twist with twist about the coordinate axis `axis` of q's own (child) frame.
/// Returns the twist angle (radians, (-pi, pi]) and the swing rotation vector (radians; its
/// component along `axis` is zero).
struct SwingTwist {
  Eigen::Vector3d swing_rad = Eigen::Vector3d::Zero();
  double twist_rad = 0;
};

inline SwingTwist swing_twist(const Eigen::Quaterniond& q_in, int axis) {
  Eigen::Quaterniond q = q_in;
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  SwingTwist st;
  const double tv = q.vec()[axis];
  const double tn = std::sqrt(q.w() * q.w() + tv * tv);
  Eigen::Quaterniond twist(1, 0, 0, 0);
  if (tn > 1e-12) {
    twist = Eigen::Quaterniond(q.w() / tn, 0, 0, 0);
    twist.vec()[axis] = tv / tn;
    st.twist_rad = 2.0 * std::atan2(tv, q.w());
    if (st.twist_rad > M_PI) st.twist_rad -= 2 * M_PI;
  }
  Eigen::Quaterniond swing = q * twist.conjugate();
  if (swing.w() < 0) swing.coeffs() = -swing.coeffs();
  const double sn = swing.vec().norm();
  if (sn > 1e-15) {
    const double ang = 2.0 * std::atan2(sn, swing.w());
    st.swing_rad = swing.vec() * (ang / sn);
  }
  st.swing_rad[axis] = 0;
  return st;
}

/// Rotation from a rotation vector (axis * angle, radians).
inline Eigen::Quaterniond from_rotation_vector(const Eigen::Vector3d& r) {
  const double a = r.norm();
  if (a < 1e-15) return Eigen::Quaterniond(1, 0.5 * r.x(), 0.5 * r.y(), 0.5 * r.z()).normalized();
  const double s = std::sin(0.5 * a) / a;
  return Eigen::Quaterniond(std::cos(0.5 * a), r.x() * s, r.y() * s, r.z() * s);
}

/// w, x, y, z as floats (PoseFrame layout) and back.
inline std::array<float, 4> to_wxyz(const Eigen::Quaterniond& q) {
  return {static_cast<float>(q.w()), static_cast<float>(q.x()), static_cast<float>(q.y()),
          static_cast<float>(q.z())};
}
inline Eigen::Quaterniond from_wxyz(const std::array<float, 4>& a) {
  return Eigen::Quaterniond(a[0], a[1], a[2], a[3]);
}

}  // namespace mocap
