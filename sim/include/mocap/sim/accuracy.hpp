// End-to-end tracking accuracy against the virtual performer's ground truth: sensor model ->
// the body tracker (rig::BodyTracker, the engine mocapd runs: gyro scale, filter per sensor,
// N-pose calibration, skeleton FK + root motion), compared frame by frame with the truth, and
// the same samples through each sensor's filter alone (the reference the body must not lose
// to), scored with the dataset README's full-body metric (segment_metric.hpp). Used by
// `mocap bench accuracy` and the regression tests.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "mocap/core/segments.hpp"
#include "mocap/sim/sensor_model.hpp"
#include "mocap/skeleton/calibration.hpp"

namespace mocap::sim {

struct AccuracyOptions {
  std::string motion = "walk";       ///< make_motion() name
  std::string disturbance = "none";  ///< disturbance_preset() name
  uint64_t seed = 1;
  double rate_hz = 100;
  double height_m = 1.75;
  SensorModelParams sensor;  ///< default: consumer MEMS errors
  /// Calibration capture: starts this long after the calibration stand begins (filters settle)
  /// and lasts capture_s (must end inside the stand).
  double settle_s = 0.8;
  double capture_s = 2.0;
  /// Body-heading source of the N-pose calibration: mount_normals (default, as the daemon) the
  /// circular mean over the sensors' site normals (skeleton/sensor_sites.hpp); pelvis_sensor
  /// the belt clip's forward axis alone (its misalignment becomes every mounting's yaw);
  /// explicit 0 = the truth. docs/accuracy.md compares them.
  HeadingSource heading = HeadingSource::mount_normals;
  double explicit_heading_deg = 0;
  /// AttitudeFilter parameter overrides ("name=value", as `mocap filter --param`), e.g. to see
  /// what a filter change would gain; default: the filter's defaults, as the daemon uses.
  std::vector<std::string> filter_params;
  /// The calibration procedure includes the calibration moves (knee bends with elbow curls,
  /// make_motion("calibrate+<motion>")) after the N-pose; the evaluation starts after them.
  bool calibration_moves = false;
  /// The calibration moves are also the mounting motion (rig/mounting_motion.hpp): each
  /// segment's facing is found from its tilt in them (only with calibration_moves).
  bool mounting_motion = true;
  /// The sensors run for 22 s of walking and turning before the calibration stand
  /// (make_motion("warmup+...")), as when a person puts them on and walks in.
  bool warmup = false;
  /// Each sensor's gyro scale calibrated first (estimate_gyro_scale on the sensor's table
  /// spins, table_spin.hpp, as a user does once per sensor; `[[sensor]] gyr_scale` in the
  /// daemon) and divided out of its samples. Off: the gyros' drawn scale errors stay.
  bool gyro_scale_calibration = false;
  /// With magnetometers (9D); false: the samples' magnetometer readings are dropped (6D rigs).
  bool use_mag = true;
  /// Pose frames per second (0: one per sample time, as the sensors sample together).
  double frame_rate_hz = 0;
  /// A dropout: the sensor on this segment sends nothing (a radio drop, a tracker rebooting)
  /// for dropout_s from dropout_start_s into the evaluated motion, while the performer moves on;
  /// both the tracker and its filter alone miss those samples. -1: none; kDropoutAll: every
  /// sensor (the receiver or the network dropped; the joint figures are over every joint).
  static constexpr int kDropoutAll = kSegmentCount;
  int dropout_segment = -1;
  double dropout_start_s = 0, dropout_s = 0;
  /// The sensors' orientations computed on the device (as a SlimeVR tracker's), so only the
  /// link drops: each filter runs on through the dropout, the body tracker sees nothing of it,
  /// and is told (TrackerSensor::fused_on_device).
  bool fused_on_device = false;
  /// Which of the performer's sensors the rig has on the body: every one, or the lower body's
  /// seven (pelvis, thighs, shanks, feet: a lab's lower-body set, as the real walk's Xsens
  /// MTw). A sensor off the rig is not on the body (filtered only) and its segment not scored.
  enum class Rig { full, lower_body };
  Rig rig = Rig::full;
  /// The scoring (and the metric's reference instant) starts this long into the motion that
  /// follows the calibration procedure; the body tracker runs from the calibration on. What a
  /// tracker finds once the person moves (a body heading no site gave, a facing) changes the
  /// alignment after the default reference instant, which the metric counts as an error over
  /// the whole clip; scored from later, the steady state is seen alone. Seconds.
  double score_after_s = 0;
  /// A long session: a BVH clip played back and forth until the motion after the calibration
  /// lasts at least this long (make_bvh_motion's session_s), so each sensor's drift grows as on
  /// a person for that long; with score_after_s, the session's end is scored alone. Seconds; 0:
  /// the clip once.
  double session_s = 0;
};

/// Segment s carries a sensor of `rig` (AccuracyOptions::rig).
bool in_rig(AccuracyOptions::Rig rig, Segment s);

struct AccuracyResult {
  std::string motion, disturbance;
  bool calibrated = false;
  std::string calibration_message;
  int frames = 0;          ///< evaluated frames (after calibration)
  double evaluated_s = 0;  ///< evaluated duration
  /// RMS of the rotation angle between estimated and true joint rotation, per joint (indexed
  /// by child segment; [0] unused), degrees.
  std::array<double, kSegmentCount> joint_rmse_deg{};
  /// RMS of the rotation angle between estimated and true earth orientation, per segment.
  std::array<double, kSegmentCount> segment_rmse_deg{};
  double hinge_max_rmse_deg = 0;      ///< worst elbow/knee
  double three_dof_max_rmse_deg = 0;  ///< worst 3-DOF joint whose parent and child carry sensors
  double inferred_max_rmse_deg = 0;   ///< worst joint touching the sensorless neck
  double segment_mean_rmse_deg = 0;   ///< mean over segments with sensors
  /// The dataset README's full-body metric (segment_metric.hpp) of the body tracker, and of the
  /// same samples through each sensor's own filter, no body model ("filters alone"; in 6D each
  /// aligned once at calibration to its sensor's true heading: the ideal a calibration reaches).
  std::array<double, kSegmentCount> metric_segment_deg{}, alone_segment_deg{};
  /// The tracker's per-segment figure under the filters-alone world rotation G (one G for both:
  /// a segment whose motion the tracker left alone scores the same; the metric's own fit per
  /// estimate lets a correction of one segment move the others' figures).
  std::array<double, kSegmentCount> metric_segment_alone_g_deg{};
  double metric_mean_deg = 0, alone_mean_deg = 0;
  /// With a dropout: the RMS of the dropped segment's joint error (to its parent; the root's:
  /// the torso's joint; kDropoutAll: over every joint) before the dropout, and from 5 s after
  /// its end to the end of the motion (how well its heading was found again), degrees; -1
  /// without such frames.
  double dropout_joint_after_deg = -1, dropout_joint_before_deg = -1;
  /// Per segment with a sensor, the largest turn between two evaluated frames beyond its
  /// sensor's filter alone's turn over them: a correction applied in one frame shows here as a
  /// snap (degrees).
  std::array<double, kSegmentCount> max_jump_deg{};
  double root_drift_m = 0;       ///< horizontal pelvis error at the end
  double root_max_error_m = 0;   ///< largest horizontal pelvis error during the motion
  double distance_walked_m = 0;  ///< true horizontal pelvis path length
  /// root_drift_m / distance_walked_m (0 when less than 1 m was walked).
  double root_drift_fraction = 0;
  // Diagnostics, per segment with a sensor (degrees):
  /// Yaw about the segment's vertical between the calibrated and the true sensor mounting.
  std::array<double, kSegmentCount> mount_yaw_error_deg{};
  /// The filter's own errors over the evaluation: RMS change of its heading error since the
  /// evaluation began (what no calibration can absorb), and RMS inclination error.
  std::array<double, kSegmentCount> sensor_heading_drift_deg{}, sensor_inclination_rmse_deg{};
  /// Fraction of evaluated frames the filter flagged the sensor's magnetometer as disturbed.
  std::array<double, kSegmentCount> sensor_mag_disturbed_fraction{};
  /// How far the performer stood from the N-pose where the site normals show it (calibration
  /// result), degrees, -1 where not observable.
  std::array<double, kSegmentCount> pose_deviation_deg{};
};

/// Joints whose both segments carry sensors and are 3-DOF (waist, shoulders, wrists, hips,
/// ankles); hinges are the elbows and knees; the two neck joints involve the sensorless neck.
bool is_measured_three_dof_joint(Segment child);
bool is_inferred_joint(Segment child);

/// Runs the motion once (no loop) through the whole pipeline. Throws std::invalid_argument for
/// unknown motion or disturbance names.
AccuracyResult run_accuracy(const AccuracyOptions& options);

}  // namespace mocap::sim
