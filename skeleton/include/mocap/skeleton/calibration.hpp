// A sensor-to-segment calibration as the skeleton applies it and as it is saved:
//
//   q_earth_segment = q_correction * q_earth_sensor * q_sensor_segment,
//
// per segment a mounting (q_sensor_segment) and an earth-frame yaw in front of the sensor's
// orientation (q_correction: a 6D sensor's own heading frame turned onto the body's, a heading
// reset), plus the pose and body heading it was taken in. Who computes and changes it: the body
// tracker's alignment (rig/alignment.hpp), from a still-pose capture (rig/pose_capture.hpp)
// and the body-heading sources (HeadingSource, rig/calibrate.hpp):
//  - pelvis_sensor: the pelvis sensor's heading axis points forward;
//  - mean_sensors: the same axis of every sensor points forward (circular mean);
//  - explicit_heading: the caller knows it (e.g. the person faces a marker);
//  - mount_normals: the sensors lie flat on their sites, z along the site's outward normal
//    (circular mean over the horizontal normals);
//  - arm_swing: N-pose then T-pose; the arms' rotation axis is the body's forward axis.
// Calibrations serialise to TOML.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <string_view>

#include "mocap/core/segments.hpp"
#include "mocap/skeleton/rig.hpp"

namespace mocap {

enum class CalibrationPose : uint8_t { npose, tpose };
enum class HeadingSource : uint8_t {
  pelvis_sensor,
  mean_sensors,
  explicit_heading,
  arm_swing,
  mount_normals
};

std::string_view to_string(CalibrationPose p);
std::string_view to_string(HeadingSource h);

/// Segment orientation relative to the body frame in a calibration pose (identity in N-pose;
/// in T-pose the arms are raised sideways: left arm +90 deg about x, right arm -90 deg).
Eigen::Quaterniond q_body_segment_in_pose(CalibrationPose pose, int segment);

struct Calibration {
  bool valid = false;
  CalibrationPose pose = CalibrationPose::npose;
  HeadingSource heading_source = HeadingSource::pelvis_sensor;
  double heading_deg = 0;  ///< body heading at calibration: earth yaw of the body x axis
  std::array<bool, kSegmentCount> calibrated{};  ///< segment had a sensor at calibration
  std::array<Eigen::Quaterniond, kSegmentCount> q_sensor_segment;
  std::array<Eigen::Quaterniond, kSegmentCount> q_correction;  ///< earth-frame yaw (heading reset)
  double motion_deg = 0;         ///< worst per-sensor RMS orientation spread during capture
  double gravity_error_deg = 0;  ///< worst per-sensor tilt disagreement with the accelerometer

  Calibration() {
    q_sensor_segment.fill(Eigen::Quaterniond::Identity());
    q_correction.fill(Eigen::Quaterniond::Identity());
  }
  /// Earth-frame segment orientation for a sensor orientation (identity mounting if the segment
  /// was not calibrated).
  Eigen::Quaterniond segment_from_sensor(int segment,
                                         const Eigen::Quaterniond& q_earth_sensor) const {
    return (q_correction[segment] * q_earth_sensor * q_sensor_segment[segment]).normalized();
  }
};

/// TOML text form ([calibration] header plus one [segment.<name>] table per calibrated segment).
std::string serialize_calibration(const Calibration& c);
/// Parses serialize_calibration's output. Throws std::runtime_error naming source:line:column
/// and the problem (unknown segment or key, bad quaternion, version mismatch).
Calibration parse_calibration(std::string_view text, std::string_view source = "calibration");
void save_calibration(const Calibration& c, const std::string& path);
Calibration load_calibration(const std::string& path);

}  // namespace mocap
