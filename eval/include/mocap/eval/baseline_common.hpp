// Shared plumbing of the baseline filters (Madgwick, Mahony): input checks, last acc/mag
// hold for multi-rate input, dt from timestamps, initial attitude from acc+mag, NWU -> ENU.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>

#include "mocap/core/imu_sample.hpp"

namespace mocap {

struct BaselineCounters {
  uint64_t nonfinite = 0, zero_vector = 0, out_of_range = 0, bad_time = 0;
};

namespace filt {

/// Holds the newest accepted acc and mag and the gyro timing.
struct BaselineInput {
  BaselineCounters counters;
  Eigen::Vector3d acc = Eigen::Vector3d::Zero(), mag = Eigen::Vector3d::Zero();
  bool have_acc = false, have_mag = false, have_t = false, initialised = false;
  int64_t t_last_ns = 0;
  double ts_nom_s = 0;

  /// Stores acc/mag of s; for a valid gyro sample returns true with dt_s (0 on the first).
  bool take(const ImuSample& s, Eigen::Vector3d& gyr, double& dt_s);
  /// take(), then sets q_nwu from the first acc (and mag if use_mag) once; true when a filter
  /// step is due with gyr and dt_s.
  bool next(const ImuSample& s, bool use_mag, Eigen::Quaterniond& q_nwu, Eigen::Vector3d& gyr,
            double& dt_s);
};

/// Orientation sensor -> North-West-Up from one acc and (optionally) one mag vector.
Eigen::Quaterniond initial_nwu(const Eigen::Vector3d& acc, const Eigen::Vector3d* mag);

/// q_enu_sensor = Rz(+90 deg) * q_nwu_sensor.
Eigen::Quaterniond nwu_to_enu(const Eigen::Quaterniond& q_nwu);

}  // namespace filt
}  // namespace mocap
