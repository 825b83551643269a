// Madgwick gradient-descent filter: one normalised gradient step of the gravity (and field)
// objective per gyro sample, Euler-integrated with the gyro rate (as in the paper).
#include "mocap/eval/madgwick.hpp"

#include <cmath>

namespace mocap {

void MadgwickFilter::update(const ImuSample& s) {
  Eigen::Vector3d gyr;
  double dt_s = 0;
  if (in_.next(s, p_.use_mag, q_nwu_, gyr, dt_s)) step(gyr, dt_s);
}

void MadgwickFilter::step(const Eigen::Vector3d& gyr, double dt_s) {
  const double q0 = q_nwu_.w(), q1 = q_nwu_.x(), q2 = q_nwu_.y(), q3 = q_nwu_.z();
  // Rate of change from the gyro: 0.5 q (x) [0, w].
  double d0 = 0.5 * (-q1 * gyr.x() - q2 * gyr.y() - q3 * gyr.z());
  double d1 = 0.5 * (q0 * gyr.x() + q2 * gyr.z() - q3 * gyr.y());
  double d2 = 0.5 * (q0 * gyr.y() - q1 * gyr.z() + q3 * gyr.x());
  double d3 = 0.5 * (q0 * gyr.z() + q1 * gyr.y() - q2 * gyr.x());

  if (in_.have_acc) {
    const Eigen::Vector3d a = in_.acc.normalized();
    // Gravity objective f_g and its Jacobian J_g (earth direction [0,0,1]).
    const double fg0 = 2 * (q1 * q3 - q0 * q2) - a.x();
    const double fg1 = 2 * (q0 * q1 + q2 * q3) - a.y();
    const double fg2 = 2 * (0.5 - q1 * q1 - q2 * q2) - a.z();
    double g0 = -2 * q2 * fg0 + 2 * q1 * fg1;
    double g1 = 2 * q3 * fg0 + 2 * q0 * fg1 - 4 * q1 * fg2;
    double g2 = -2 * q0 * fg0 + 2 * q3 * fg1 - 4 * q2 * fg2;
    double g3 = 2 * q1 * fg0 + 2 * q2 * fg1;
    if (p_.use_mag && in_.have_mag) {
      const Eigen::Vector3d m = in_.mag.normalized();
      // Earth-frame field h = q m q*, reference b = [|h_xy|, 0, h_z].
      const Eigen::Vector3d h = q_nwu_ * m;
      const double bx = std::sqrt(h.x() * h.x() + h.y() * h.y()), bz = h.z();
      // Field objective f_b for d = [bx, 0, bz] and its Jacobian (Madgwick 2010, eqs 29-30).
      const double fb0 = 2 * bx * (0.5 - q2 * q2 - q3 * q3) + 2 * bz * (q1 * q3 - q0 * q2) - m.x();
      const double fb1 = 2 * bx * (q1 * q2 - q0 * q3) + 2 * bz * (q0 * q1 + q2 * q3) - m.y();
      const double fb2 = 2 * bx * (q0 * q2 + q1 * q3) + 2 * bz * (0.5 - q1 * q1 - q2 * q2) - m.z();
      g0 += -2 * bz * q2 * fb0 + (-2 * bx * q3 + 2 * bz * q1) * fb1 + 2 * bx * q2 * fb2;
      g1 +=
          2 * bz * q3 * fb0 + (2 * bx * q2 + 2 * bz * q0) * fb1 + (2 * bx * q3 - 4 * bz * q1) * fb2;
      g2 += (-4 * bx * q2 - 2 * bz * q0) * fb0 + (2 * bx * q1 + 2 * bz * q3) * fb1 +
            (2 * bx * q0 - 4 * bz * q2) * fb2;
      g3 += (-4 * bx * q3 + 2 * bz * q1) * fb0 + (-2 * bx * q0 + 2 * bz * q2) * fb1 +
            2 * bx * q1 * fb2;
    }
    const double gn = std::sqrt(g0 * g0 + g1 * g1 + g2 * g2 + g3 * g3);
    if (gn > 1e-12) {
      const double k = p_.beta_rad_s / gn;
      d0 -= k * g0;
      d1 -= k * g1;
      d2 -= k * g2;
      d3 -= k * g3;
    }
  }
  q_nwu_ = Eigen::Quaterniond(q0 + d0 * dt_s, q1 + d1 * dt_s, q2 + d2 * dt_s, q3 + d3 * dt_s);
  q_nwu_.normalize();
}

}  // namespace mocap
