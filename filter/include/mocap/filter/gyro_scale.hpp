// Gyro scale calibration from whole turns on a table: a one-time per-sensor calibration.
//
// Why: a consumer MEMS gyro's sensitivity is off by ~0.5 % per axis, so a person turning 180 deg
// turns each sensor's heading by a different 1-3 deg, which only the magnetometers correct, over
// seconds (docs/accuracy.md: the hip after a turn). Measured once per sensor, the error is gone.
//
// How: the sensor lies on a table, is spun a whole number of turns about one of its axes (the
// axis vertical), and put down again; the rests before and after each spin give the bias, and
// the gyro's integral over the spin should be 360 deg x turns plus the net change of heading
// between the two rests. That net change is read from the magnetometer (the field's direction
// about the spin axis at the two rests, after the hard-iron offset across the axis is taken out:
// the centre of the circle the field draws during the spin), or taken as 0 without one (the
// sensor put back against a stop). Every spin about an axis adds to that axis's estimate; axes
// never spun keep scale 1.
#pragma once

#include <Eigen/Core>
#include <array>
#include <span>
#include <string>

#include "mocap/core/imu_sample.hpp"

namespace mocap {

struct GyroScaleOptions {
  double still_deg_s = 5.0;        ///< |gyro| below this counts as still (bias included)
  double min_rest_s = 0.5;         ///< shortest rest between spins
  double min_turn_deg = 300;       ///< a spin turns at least this much about its axis
  double max_off_axis = 0.05;      ///< other axes' integral, as a fraction of the spin axis's
  double max_tilt_change_deg = 5;  ///< gravity direction change between the two rests
  double max_net_turn_deg = 45;    ///< the net heading change must be within this of n turns
};

struct GyroScaleAxis {
  int spins = 0;            ///< spins about this axis used
  double measured_deg = 0;  ///< the gyro's integral over them (bias removed)
  double true_deg = 0;      ///< 360 x turns + net heading change, summed
  double scale = 1;         ///< measured / true (1 when never spun)
};

struct GyroScaleResult {
  std::array<GyroScaleAxis, 3> axis;
  int rests = 0;           ///< rests found
  int rejected_spins = 0;  ///< motions between rests that were not a clean spin
  Eigen::Vector3d scale() const {
    return Eigen::Vector3d(axis[0].scale, axis[1].scale, axis[2].scale);
  }
};

/// One sensor's samples (time order; gyro required, acc for the tilt check, mag optional).
GyroScaleResult estimate_gyro_scale(std::span<const ImuSample> samples,
                                    const GyroScaleOptions& options = {});

}  // namespace mocap
