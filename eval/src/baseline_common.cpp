// Input handling and initialisation shared by the Madgwick and Mahony baselines.
#include "mocap/eval/baseline_common.hpp"

#include <algorithm>
#include <cmath>

#include "mocap/filter/input_check.hpp"

namespace mocap::filt {

bool BaselineInput::take(const ImuSample& s, Eigen::Vector3d& gyr, double& dt_s) {
  if (s.has(kFieldAcc) && check_vector(s.acc_m_s2, 1e-3, 500.0, counters)) {
    acc = s.acc_m_s2;
    have_acc = true;
  }
  if (s.has(kFieldMag) && check_vector(s.mag_uT, 1e-6, 1e4, counters)) {
    mag = s.mag_uT;
    have_mag = true;
  }
  if (!s.has(kFieldGyr) || !check_vector(s.gyr_rad_s, 0.0, 70.0, counters)) return false;
  if (!have_t) {
    have_t = true;
    t_last_ns = s.t_host_ns;
    dt_s = 0;
  } else {
    if (s.t_host_ns <= t_last_ns) {
      ++counters.bad_time;
      return false;
    }
    dt_s = std::min(static_cast<double>(s.t_host_ns - t_last_ns) * 1e-9, 0.25);
    t_last_ns = s.t_host_ns;
  }
  gyr = s.gyr_rad_s;
  return true;
}

bool BaselineInput::next(const ImuSample& s, bool use_mag, Eigen::Quaterniond& q_nwu,
                         Eigen::Vector3d& gyr, double& dt_s) {
  if (!take(s, gyr, dt_s)) return false;
  if (initialised) return true;
  if (have_acc) {
    q_nwu = initial_nwu(acc, use_mag && have_mag ? &mag : nullptr);
    initialised = true;
  }
  return false;
}

Eigen::Quaterniond initial_nwu(const Eigen::Vector3d& acc, const Eigen::Vector3d* mag) {
  const Eigen::Vector3d z = acc.normalized();  // up, in sensor coordinates
  Eigen::Vector3d x;                           // north, in sensor coordinates
  if (mag) x = *mag - mag->dot(z) * z;
  if (!mag || x.norm() < 1e-9) {
    x = Eigen::Vector3d::UnitX() - z.x() * z;
    if (x.norm() < 1e-6) x = Eigen::Vector3d::UnitY() - z.y() * z;
  }
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d r_sensor_earth;  // columns: earth axes in sensor coordinates
  r_sensor_earth.col(0) = x;
  r_sensor_earth.col(1) = y;
  r_sensor_earth.col(2) = z;
  return Eigen::Quaterniond(Eigen::Matrix3d(r_sensor_earth.transpose())).normalized();
}

Eigen::Quaterniond nwu_to_enu(const Eigen::Quaterniond& q_nwu) {
  constexpr double h = 0.70710678118654752440;
  return Eigen::Quaterniond(h, 0, 0, h) * q_nwu;
}

}  // namespace mocap::filt
