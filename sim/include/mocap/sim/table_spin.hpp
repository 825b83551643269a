// The gyro scale calibration as a user performs it (estimate_gyro_scale): the sensor on a
// table, each of its axes vertical in turn, spun whole turns with rests between, measured by a
// virtual sensor's error model.
#pragma once

#include <vector>

#include "mocap/core/imu_sample.hpp"
#include "mocap/sim/sensor_model.hpp"

namespace mocap::sim {

/// Samples of `model` (a copy: the caller's stream is untouched) at rate_hz: for each sensor
/// axis x, y, z: 2 s still with that axis up, `turns` whole turns plus extra_deg at up to
/// ~200 deg/s, 2 s still, then a 90 deg flip onto the next axis. sensor_id 0, t from 0.
std::vector<ImuSample> table_spin_samples(SensorErrorModel model, const MagneticFieldParams& field,
                                          double rate_hz, int turns = 3, double extra_deg = 0);

/// What `mocap gyro-scale` measures on the sensor's table spins (default field, three turns per
/// axis): the gyr_scale a user would configure for it.
Eigen::Vector3d calibrated_gyro_scale(const SensorErrorModel& model, double rate_hz);

}  // namespace mocap::sim
