// End-to-end tracking accuracy against the virtual performer's ground truth: sensor model ->
// AttitudeFilter per sensor -> N-pose calibration (Calibrator) -> Skeleton (FK + root motion),
// compared frame by frame with the truth. Used by `mocap bench accuracy` and the regression test.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "mocap/core/segments.hpp"
#include "mocap/sim/sensor_model.hpp"
#include "mocap/skeleton/calibration.hpp"
#include "mocap/skeleton/heading_coupling.hpp"
#include "mocap/skeleton/hinge_calibration.hpp"
#include "mocap/skeleton/relative_mag_heading.hpp"

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
  /// Hinge-motion refinement of the calibration (on by default, as in the daemon).
  HingeRefineOptions hinge_refine{};
  /// Heading coupling at the knees and elbows (heading_coupling.hpp), as the daemon's
  /// calibration.heading_coupling (on by default in both).
  HeadingCouplingOptions heading_coupling{.enabled = true};
  /// Relative magnetometer heading smoothing (relative_mag_heading.hpp), as the daemon's
  /// calibration.relative_mag_heading (on by default in both).
  RelativeMagHeadingOptions relative_mag_heading{.enabled = true};
  /// AttitudeFilter parameter overrides ("name=value", as `mocap filter --param`), e.g. to see
  /// what a filter change would gain; default: the filter's defaults, as the daemon uses.
  std::vector<std::string> filter_params;
  /// The calibration procedure includes the calibration moves (knee bends with elbow curls,
  /// make_motion("calibrate+<motion>")) after the N-pose; the evaluation starts after them.
  bool calibration_moves = false;
  /// The sensors run for 22 s of walking and turning before the calibration stand
  /// (make_motion("warmup+...")), as when a person puts them on and walks in.
  bool warmup = false;
  /// Anchor each filter's heading at the N-pose calibration (AttitudeFilter::anchor_heading(),
  /// as the daemon does): a hard-iron offset learnt later does not turn the calibration.
  bool anchor_heading = true;
  /// Rig consensus of the reference field (filt::RigFieldConsensus, as the daemon): a sensor
  /// whose reference field differs from the median of the others' gets the median.
  bool rig_consensus = true;
  /// Each sensor's gyro scale calibrated first (filt::estimate_gyro_scale on the sensor's table
  /// spins, table_spin.hpp, as a user does once per sensor; `[[sensor]] gyr_scale` in the
  /// daemon) and divided out of its samples. Off: the gyros' drawn scale errors stay.
  bool gyro_scale_calibration = false;
};

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
  double root_drift_m = 0;            ///< horizontal pelvis error at the end
  double root_max_error_m = 0;        ///< largest horizontal pelvis error during the motion
  double distance_walked_m = 0;       ///< true horizontal pelvis path length
  /// root_drift_m / distance_walked_m (0 when less than 1 m was walked).
  double root_drift_fraction = 0;
  // Diagnostics, per segment with a sensor (degrees):
  /// Yaw about the segment's vertical between the calibrated and the true sensor mounting: of
  /// the N-pose calibration, and of the calibration in use at the end (after hinge refinement).
  std::array<double, kSegmentCount> npose_mount_yaw_error_deg{}, mount_yaw_error_deg{};
  /// The filter's own errors over the evaluation: RMS change of its heading error since the
  /// evaluation began (what no calibration can absorb), and RMS inclination error.
  std::array<double, kSegmentCount> sensor_heading_drift_deg{}, sensor_inclination_rmse_deg{};
  /// Fraction of evaluated frames the filter flagged the sensor's magnetometer as disturbed.
  std::array<double, kSegmentCount> sensor_mag_disturbed_fraction{};
  /// The filter's reference field was imposed by the rig consensus (at the end), and the
  /// heading error its trust anchor keeps (AttitudeFilter::anchor_trust_rad), degrees.
  std::array<bool, kSegmentCount> sensor_ref_imposed{};
  std::array<double, kSegmentCount> sensor_anchor_trust_deg{};
  int hinges_identified = 0;  ///< knees/elbows whose axis the refinement identified
  std::array<HingeEstimate, kRefinePairs.size()> hinges{};      ///< the refinement's state
  std::array<CouplingHinge, kCouplingPairs.size()> coupling{};  ///< the heading coupling's
};

/// Joints whose both segments carry sensors and are 3-DOF (waist, shoulders, wrists, hips,
/// ankles); hinges are the elbows and knees; the two neck joints involve the sensorless neck.
bool is_measured_three_dof_joint(Segment child);
bool is_inferred_joint(Segment child);

/// Runs the motion once (no loop) through the whole pipeline. Throws std::invalid_argument for
/// unknown motion or disturbance names.
AccuracyResult run_accuracy(const AccuracyOptions& options);

}  // namespace mocap::sim
