// Mahony complementary filter: correction w_mes = sum v_i x v_hat_i, PI feedback, Euler step.
#include "mocap/eval/mahony.hpp"

#include <cmath>

namespace mocap {

void MahonyFilter::update(const ImuSample& s) {
  Eigen::Vector3d gyr;
  double dt_s = 0;
  if (!in_.next(s, p_.use_mag, q_nwu_, gyr, dt_s)) return;
  Eigen::Vector3d w_mes = Eigen::Vector3d::Zero();
  if (in_.have_acc) {
    const Eigen::Quaterniond qc = q_nwu_.conjugate();
    const Eigen::Vector3d a = in_.acc.normalized();
    w_mes += a.cross(qc * Eigen::Vector3d::UnitZ());  // measured x predicted gravity
    if (p_.use_mag && in_.have_mag) {
      const Eigen::Vector3d m = in_.mag.normalized();
      const Eigen::Vector3d h = q_nwu_ * m;
      const Eigen::Vector3d b(std::sqrt(h.x() * h.x() + h.y() * h.y()), 0, h.z());
      w_mes += m.cross(qc * b);
    }
  }
  integral_rad_s_ += p_.ki_rad_s2 * w_mes * dt_s;
  const Eigen::Vector3d w = gyr + p_.kp_rad_s * w_mes + integral_rad_s_;
  const Eigen::Quaterniond dq(0, 0.5 * w.x() * dt_s, 0.5 * w.y() * dt_s, 0.5 * w.z() * dt_s);
  Eigen::Quaterniond q = q_nwu_ * dq;
  q_nwu_ = Eigen::Quaterniond(q_nwu_.w() + q.w(), q_nwu_.x() + q.x(), q_nwu_.y() + q.y(),
                              q_nwu_.z() + q.z());
  q_nwu_.normalize();
}

}  // namespace mocap
