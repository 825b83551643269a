// Madgwick's gradient-descent orientation filter (Madgwick 2010 report; ICORR 2011), written
// from the paper as a baseline, with the earth-field reference b = [|h_xy|, 0, h_z] computed
// at full magnitude (no "x2 bug"). Earth frame of the algorithm is North-West-Up; outputs are
// rotated into ENU.
#pragma once

#include <Eigen/Geometry>

#include "mocap/core/imu_sample.hpp"
#include "mocap/eval/baseline_common.hpp"

namespace mocap {

struct MadgwickParams {
  double beta_rad_s = 0.12;  ///< gradient step rate (BROAD-tuned value from the benchmark)
  bool use_mag = true;       ///< false: 6D (IMU) update only
};

class MadgwickFilter {
 public:
  explicit MadgwickFilter(const MadgwickParams& p = {}) : p_(p) {}
  void update(const ImuSample& s);
  Eigen::Quaterniond q_earth_sensor() const { return filt::nwu_to_enu(q_nwu_); }
  const BaselineCounters& counters() const { return in_.counters; }

 private:
  void step(const Eigen::Vector3d& gyr, double dt_s);
  MadgwickParams p_;
  Eigen::Quaterniond q_nwu_ = Eigen::Quaterniond::Identity();
  filt::BaselineInput in_;
};

}  // namespace mocap
