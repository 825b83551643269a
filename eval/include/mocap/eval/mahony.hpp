// Mahony's explicit complementary filter with bias integrator (Mahony, Hamel, Pflimlin, IEEE
// TAC 53(5), 2008), written from the paper as a baseline. Earth frame North-West-Up internally,
// outputs rotated into ENU.
#pragma once

#include <Eigen/Geometry>

#include "mocap/core/imu_sample.hpp"
#include "mocap/eval/baseline_common.hpp"

namespace mocap {

struct MahonyParams {
  double kp_rad_s = 1.48;     ///< proportional gain (2 x 0.74, the BROAD-tuned x-io value)
  double ki_rad_s2 = 0.0024;  ///< integral gain (2 x 0.0012)
  bool use_mag = true;        ///< false: 6D update only
};

class MahonyFilter {
 public:
  explicit MahonyFilter(const MahonyParams& p = {}) : p_(p) {}
  void update(const ImuSample& s);
  Eigen::Quaterniond q_earth_sensor() const { return filt::nwu_to_enu(q_nwu_); }
  Eigen::Vector3d gyro_bias_rad_s() const { return -integral_rad_s_; }
  const BaselineCounters& counters() const { return in_.counters; }

 private:
  MahonyParams p_;
  Eigen::Quaterniond q_nwu_ = Eigen::Quaterniond::Identity();
  Eigen::Vector3d integral_rad_s_ = Eigen::Vector3d::Zero();
  filt::BaselineInput in_;
};

}  // namespace mocap
