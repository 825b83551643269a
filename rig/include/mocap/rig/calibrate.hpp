// A calibration from a still-pose capture: the facings the configured sources give, the body
// heading, the alignment (alignment.hpp), and a report of what could not be determined.
// Never refused for want of standard sites: a sensor not on one (or without a facing) is
// aligned by its capture's up axis and reported; its mounting yaw and, in 6D, its heading come
// from motion later (mounting_motion.hpp, joint_heading.hpp). Only a capture that could not
// measure (too few samples, motion, attitude off gravity) is refused.
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>

#include "mocap/rig/alignment.hpp"
#include "mocap/rig/pose_capture.hpp"

namespace mocap::rig {

/// Where the body heading and the facings come from (the configured part of a calibration).
struct CalibrationSetup {
  /// Body-heading source: mount_normals (default) the sites' normals (site_normal_body);
  /// pelvis_sensor / mean_sensors a sensor axis pointing forward (heading_axis_sensor);
  /// explicit_heading a given heading; arm_swing an N-pose then a T-pose capture.
  HeadingSource heading = HeadingSource::mount_normals;
  Eigen::Vector3d heading_axis_sensor = Eigen::Vector3d::UnitX();
  double explicit_heading_deg = 0;
  /// Each segment's site normal in the N-pose body frame (the sensor's z axis along it); zero:
  /// none (the sensor's facing is then found from motion).
  std::array<Eigen::Vector3d, kSegmentCount> site_normal_body = [] {
    std::array<Eigen::Vector3d, kSegmentCount> zero;  // Eigen does not zero on construction
    zero.fill(Eigen::Vector3d::Zero());
    return zero;
  }();
};

enum class CalibrationStatus : uint8_t {
  ok,          ///< calibration computed
  need_tpose,  ///< arm_swing: N-pose captured, capture the T-pose next
  refused,     ///< the capture could not measure: see message
};

struct CalibrationResult {
  CalibrationStatus status = CalibrationStatus::refused;
  Calibration calibration;                                ///< valid when status == ok
  std::array<double, kSegmentCount> motion_deg{};         ///< per-segment RMS spread
  std::array<double, kSegmentCount> gravity_error_deg{};  ///< per-segment, -1 without acc
  std::array<int, kSegmentCount> samples{};
  /// How far each segment was from the assumed pose where its site normal shows it: the tilt
  /// of the normal against the pose's, degrees (-1: not observable). Reported, not refused.
  std::array<double, kSegmentCount> pose_deviation_deg{};
  /// Each segment's facing at the capture as the sources gave it (unknown: from motion later).
  std::array<Facing, kSegmentCount> facing{};
  /// Sensors sharing the earth frame whose facing disagreed with the body heading by more than
  /// kLocalFieldDeg (rad, 0 elsewhere): their filter may have taken a local field (a magnet,
  /// steel) for north, or the pose is turned there.
  std::array<double, kSegmentCount> heading_off_normal_rad{};
  static constexpr double kLocalFieldDeg = 20.0;
  bool body_heading_known = false;
  std::string message;  ///< verdict naming the segments: refused, undetermined, off
  bool ok() const { return status == CalibrationStatus::ok; }
};

/// Runs the calibration of a judged capture into `out`. `own_frame`: the segments whose
/// sensors have a heading frame of their own (6D). `npose` (arm_swing only): the N-pose capture
/// before this T-pose one, or none (the result then asks for the T-pose).
CalibrationResult calibrate(const PoseCapturer::Result& capture, const CalibrationSetup& setup,
                            const std::array<bool, kSegmentCount>& own_frame,
                            const PoseCapture* npose, Alignment& out);

}  // namespace mocap::rig
