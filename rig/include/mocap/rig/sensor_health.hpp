// One sensor's health as the body tracker knows it: produced once (BodyTracker::sensor_health),
// turned into the SegmentFlag bits once (segment_flags: the skeleton's input flags and every
// frame's SensorStatus::flags), and read from there by the status report, the viewer and the
// recordings. Nothing else restates it.
#pragma once

#include <cstdint>

#include "mocap/skeleton/pose_frame.hpp"

namespace mocap::rig {

struct SensorHealth {
  bool at_rest = false;
  bool mag_disturbed = false;     ///< field rejected (9D only)
  bool mag_no_reference = false;  ///< 9D heading still provisional (no reference field yet)
  bool calibrated = false;        ///< a sensor-to-segment calibration is applied
  double gyro_bias_rad_s = 0;     ///< norm of the filter's bias estimate
  double heading_sigma_rad = 0;   ///< the 9D heading's one-sigma (0 in 6D)

  /// kSegAtRest, kSegMagDisturbed, kSegMagNoReference, kSegCalibrated as they apply.
  uint32_t segment_flags() const {
    return (at_rest ? uint32_t{kSegAtRest} : 0u) |
           (mag_disturbed ? uint32_t{kSegMagDisturbed} : 0u) |
           (mag_no_reference ? uint32_t{kSegMagNoReference} : 0u) |
           (calibrated ? uint32_t{kSegCalibrated} : 0u);
  }
};

}  // namespace mocap::rig
