// Sensor-to-segment calibration. The person stands still in a known pose (N-pose or T-pose) for
// ~2 s; the Calibrator averages each sensor's earth-frame orientation, checks that nobody moved
// and that the attitude agrees with gravity, and computes each sensor's mounting rotation on its
// segment (q_sensor_segment) and the common body heading. A heading-only reset re-aligns every
// segment's heading to the pelvis later (drift of 6-D filters). Calibrations serialise to TOML.
//
// With the calibration, q_earth_segment = q_correction * q_earth_sensor * q_sensor_segment,
// where q_correction is an earth-frame yaw set by heading resets (identity after calibration).
//
// Heading (the direction the person faces, yaw of the body's x axis in the earth frame) is not
// observable from one static pose when sensors are mounted arbitrarily. Sources:
//  - pelvis_sensor: the pelvis sensor's `heading_axis_sensor` points forward (default +x);
//  - mean_sensors: the same axis of every sensor points forward (circular mean);
//  - explicit_heading: the caller knows it (e.g. the person faces a marker);
//  - mount_normals: every sensor lies flat on its segment, its `heading_axis_sensor` along the
//    surface's outward normal, whose body-frame direction in the pose is known per segment
//    (`mount_normal_body`; a strap's roll about it may be anything). The heading is the circular
//    mean over the sensors with a horizontal normal: each sensor's misalignment and filter
//    heading error count 1/N instead of the pelvis sensor's counting fully;
//  - arm_swing: N-pose then T-pose; the arms' rotation axis is the body's forward axis. Works for
//    any mounting of every sensor (needs sensors on both or either upper arm).
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

/// Heading-only reset (the person stands upright facing forward): each tracked segment's earth
/// yaw is re-aligned to the pelvis's (or the circular mean when the pelvis has no sensor), or to
/// `target_heading_rad` when given (e.g. 0: the performer faces +x, east, afterwards).
/// `q_earth_sensor` holds the latest orientation per segment; `have` says which are valid.
void apply_heading_reset(Calibration& c,
                         const std::array<Eigen::Quaterniond, kSegmentCount>& q_earth_sensor,
                         const std::array<bool, kSegmentCount>& have,
                         const double* target_heading_rad = nullptr);

struct CalibratorOptions {
  double capture_s = 2.0;                ///< capture duration
  double min_sample_fraction = 0.5;      ///< each sensor needs >= this * capture_s * 10 Hz samples
  double max_motion_deg = 2.0;           ///< refuse if a sensor's RMS spread exceeds this
  double max_gravity_error_deg = 5.0;    ///< refuse if attitude and accelerometer disagree more
  double max_acc_norm_error_m_s2 = 0.8;  ///< refuse if |acc| departs this far from g (moving)
  HeadingSource heading = HeadingSource::pelvis_sensor;
  Eigen::Vector3d heading_axis_sensor = Eigen::Vector3d::UnitX();  ///< for pelvis/mean sources
  double explicit_heading_deg = 0;                                 ///< for explicit_heading
  /// mount_normals: the outward normal of each segment's sensor site in the body frame (in the
  /// calibration pose); zero = unknown (segment not used for the heading).
  std::array<Eigen::Vector3d, kSegmentCount> mount_normal_body = [] {
    std::array<Eigen::Vector3d, kSegmentCount> zero;  // Eigen does not zero on construction
    zero.fill(Eigen::Vector3d::Zero());
    return zero;
  }();
  /// Segments whose sensor's filter has a heading frame of its own (no magnetometer: 6D rigs,
  /// or a sensor that sends none). With mount_normals each such sensor's heading is aligned on
  /// its own from its site's normal (q_correction) onto the body heading the others agree on (0
  /// when none has a magnetometer); such a segment whose site normal is near vertical (head,
  /// feet) takes the alignment of the nearest such segment above it that has one (the body
  /// tracker then finds its own from motion, rig/heading_from_motion.hpp).
  std::array<bool, kSegmentCount> own_heading_frame{};
};

enum class CalibrationStatus : uint8_t {
  ok,          ///< calibration computed and within quality limits
  need_tpose,  ///< arm_swing: N-pose captured, capture the T-pose next
  refused,     ///< quality too poor or sensors missing: see message
};

struct CalibrationResult {
  CalibrationStatus status = CalibrationStatus::refused;
  Calibration calibration;                                ///< valid when status == ok
  std::array<double, kSegmentCount> motion_deg{};         ///< per-segment RMS spread
  std::array<double, kSegmentCount> gravity_error_deg{};  ///< per-segment, -1 without acc
  std::array<int, kSegmentCount> samples{};
  /// How far each segment was from the assumed pose where its site normal shows it: the tilt
  /// of the normal against the pose's, degrees (-1: not observable). Reported, not refused: a
  /// constant offset does not change the tracked motion.
  std::array<double, kSegmentCount> pose_deviation_deg{};
  /// own_heading_frame segments: the heading alignment came from the segment's own site normal;
  /// false where it was borrowed from a segment above (head, feet), to be found from motion.
  std::array<bool, kSegmentCount> heading_from_own_normal{};
  /// Sensors sharing the earth frame (magnetometer) whose heading disagreed with their site
  /// normal by more than kLocalFieldDeg (rad, 0 elsewhere): their filter may have taken a local
  /// field (a magnet, steel) for north, or the pose is turned there. BodyTracker has the filter
  /// watch it (AttitudeFilter::suspect_local_field) and fixes the mounting if confirmed.
  std::array<double, kSegmentCount> heading_off_normal_rad{};
  static constexpr double kLocalFieldDeg = 20.0;
  std::string message;  ///< human-readable verdict naming the offending segments
  bool ok() const { return status == CalibrationStatus::ok; }
};

/// Collects samples during a capture. Preallocates nothing per sample: running sums only
/// (sum of q q^T for the mean and spread, sum of earth-frame specific force).
class Calibrator {
 public:
  explicit Calibrator(RigMapping rig, CalibratorOptions options = {});

  /// Starts a capture in `pose`; samples before t_start_ns are ignored.
  void start(CalibrationPose pose, int64_t t_start_ns);
  /// One orientation sample of the sensor on `segment`; acc_sensor_m_s2 optional (specific
  /// force in the sensor frame) for the gravity check.
  void add_sample(int segment, const Eigen::Quaterniond& q_earth_sensor, int64_t t_ns,
                  const Eigen::Vector3d* acc_sensor_m_s2 = nullptr);
  bool capturing() const { return capturing_; }
  /// Fraction of the capture elapsed at t_ns (0..1).
  double progress(int64_t t_ns) const;
  bool done(int64_t t_ns) const { return capturing_ && progress(t_ns) >= 1.0; }
  /// Ends the capture and evaluates it.
  CalibrationResult finish();
  const CalibratorOptions& options() const { return opt_; }
  /// Which segments' sensors have a heading frame of their own (set before a capture ends).
  void set_own_heading_frames(const std::array<bool, kSegmentCount>& own) {
    opt_.own_heading_frame = own;
  }

 private:
  struct Accum {
    Eigen::Matrix4d qq = Eigen::Matrix4d::Zero();
    Eigen::Vector3d acc_earth = Eigen::Vector3d::Zero();
    double acc_norm_sum = 0;
    double acc_norm_max_dev = 0;
    int n = 0, n_acc = 0;
  };
  RigMapping rig_;
  CalibratorOptions opt_;
  CalibrationPose pose_ = CalibrationPose::npose;
  bool capturing_ = false;
  int64_t t_start_ns_ = 0, t_last_ns_ = 0;
  std::array<Accum, kSegmentCount> acc_{};
  // Mean orientations of the last accepted N-pose capture (for arm_swing).
  bool have_npose_ = false;
  std::array<Eigen::Quaterniond, kSegmentCount> npose_mean_;
};

}  // namespace mocap
