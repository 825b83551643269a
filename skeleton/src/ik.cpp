// Two-bone analytic IK.
#include "mocap/skeleton/ik.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace mocap {

namespace {

Eigen::Vector3d any_perpendicular(const Eigen::Vector3d& d) {
  const Eigen::Vector3d a =
      std::abs(d.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  return (a - d * d.dot(a)).normalized();
}

// Rotation taking the orthonormal pair (d_from, y_from) onto (d_to, y_to).
Eigen::Quaterniond frame_rotation(const Eigen::Vector3d& d_from, const Eigen::Vector3d& y_from,
                                  const Eigen::Vector3d& d_to, const Eigen::Vector3d& y_to) {
  Eigen::Matrix3d a, b;
  a << d_from, y_from, d_from.cross(y_from);
  b << d_to, y_to, d_to.cross(y_to);
  return Eigen::Quaterniond(Eigen::Matrix3d(b * a.transpose())).normalized();
}

}  // namespace

TwoBoneIk solve_two_bone_ik(const Eigen::Vector3d& root, double l1, double l2,
                            const Eigen::Vector3d& target, const Eigen::Vector3d& hint) {
  TwoBoneIk r;
  Eigen::Vector3d d = target - root;
  double dist = d.norm();
  d = dist > 1e-12 ? Eigen::Vector3d(d / dist) : Eigen::Vector3d(0, 0, -1);
  Eigen::Vector3d m = hint - d * d.dot(hint);
  m = m.norm() > 1e-9 ? Eigen::Vector3d(m.normalized()) : any_perpendicular(d);
  const double lo = std::abs(l1 - l2), hi = l1 + l2;
  r.reached = dist >= lo && dist <= hi;
  dist = std::clamp(dist, lo, hi);
  // Angle at the root between the target direction and the upper bone.
  const double cos_a =
      dist > 1e-12 ? std::clamp((l1 * l1 + dist * dist - l2 * l2) / (2 * l1 * dist), -1.0, 1.0)
                   : 1.0;
  const double sin_a = std::sqrt(std::max(0.0, 1 - cos_a * cos_a));
  r.p_mid_m = root + l1 * (cos_a * d + sin_a * m);
  r.p_end_m = root + dist * d;
  return r;
}

TwoBoneIk solve_limb_ik(const BodyModel& model, Segment upper, const Eigen::Vector3d& p_upper_m,
                        const Eigen::Vector3d& target, const Eigen::Vector3d& hint,
                        std::array<Eigen::Quaterniond, kSegmentCount>& q) {
  const int u = index(upper);
  const bool leg = upper == Segment::thigh_l || upper == Segment::thigh_r;
  if (!leg && upper != Segment::upper_arm_l && upper != Segment::upper_arm_r)
    throw std::invalid_argument("solve_limb_ik: upper must be a thigh or an upper arm");
  const int mid = u + 1, end = u + 2;  // depth-first order: upper, lower, hand/foot
  const Eigen::Vector3d off1 = model.joint_offset_m(mid), off2 = model.joint_offset_m(end);
  const TwoBoneIk r = solve_two_bone_ik(p_upper_m, off1.norm(), off2.norm(), target, hint);
  const Eigen::Vector3d dir1 = (r.p_mid_m - p_upper_m).normalized();
  const Eigen::Vector3d dir2 = (r.p_end_m - r.p_mid_m).normalized();
  // Bend-plane normal m x d (see docs/skeleton.md); knees flex about +y, elbows about -y.
  Eigen::Vector3d d = (r.p_end_m - p_upper_m);
  d = d.norm() > 1e-12 ? Eigen::Vector3d(d.normalized()) : dir1;
  Eigen::Vector3d m = hint - d * d.dot(hint);
  m = m.norm() > 1e-9 ? Eigen::Vector3d(m.normalized()) : any_perpendicular(d);
  const Eigen::Vector3d n = m.cross(d).normalized();
  const Eigen::Vector3d y_earth = leg ? n : Eigen::Vector3d(-n);
  const Eigen::Vector3d y = Eigen::Vector3d::UnitY();
  const Eigen::Vector3d bone1 = off1.normalized(), bone2 = off2.normalized();
  // The bones' N-pose directions must be perpendicular to y (true for the anthropometric model).
  auto ortho = [&](const Eigen::Vector3d& b) {
    return Eigen::Vector3d((b - y * b.dot(y)).normalized());
  };
  q[u] = frame_rotation(ortho(bone1), y, dir1, y_earth);
  q[mid] = frame_rotation(ortho(bone2), y, dir2, y_earth);
  return r;
}

}  // namespace mocap
