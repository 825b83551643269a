// The body tracker: inertial samples in, a posture out. It owns, in this order per sample:
//   1. the sensor's gyro scale (its one-time table-spin calibration, divided out),
//   2. the sensor's AttitudeFilter (9D, or 6D without magnetometers), or for an orientation
//      source (a sample with q_device_sensor and no gyro, e.g. a SlimeVR tracker) its own
//      orientation (z-up earth frame, heading its own, aligned at calibration like 6D),
//   3. the calibration capture (N-/T-pose, Calibrator), which turns each sensor's orientation
//      into its segment's (mounting, and in 6D each sensor's own heading from its site normal),
//   4. in 6D, the heading alignment from motion of the sensors whose site normal is vertical
//      (head, feet: heading_from_motion.hpp), a constant per sensor once found,
//   5. the skeleton's input (orientation and flags);
// and per frame the skeleton solve (each segment holds its sensor's newest orientation).
//
// Nothing between the filter and the segment changes a segment's motion: a segment is its own
// sensor's filter output through a constant calibration, so the body can never make a segment
// worse than its sensor's filter alone (docs/accuracy.md shows why every body-level correction
// tried so far was removed). mocapd, mocap replay, mocap bench accuracy and the tests all run
// this class; it knows no configuration file, clock or thread.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <vector>

#include "mocap/core/imu_sample.hpp"
#include "mocap/filter/attitude_filter.hpp"
#include "mocap/rig/heading_from_motion.hpp"
#include "mocap/rig/sensor_health.hpp"
#include "mocap/skeleton/calibration.hpp"
#include "mocap/skeleton/skeleton.hpp"

namespace mocap::rig {

/// One sensor of the rig. A sensor that sends no magnetometer samples is taken as 6D even in a
/// 9D rig (its heading aligned at calibration on its own, like a 6D rig's).
struct TrackerSensor {
  int segment = -1;  ///< segment index it is strapped on, -1: not on the body (filtered only)
  /// Gyro scale per axis from the sensor's table-spin calibration (1 = uncalibrated).
  Eigen::Vector3d gyr_scale = Eigen::Vector3d::Ones();
  /// Outward normal of its site in the body frame (the sensor's z axis lies along it); zero:
  /// the segment's standard site (skeleton/sensor_sites.hpp).
  Eigen::Vector3d site_normal_body = Eigen::Vector3d::Zero();
};

struct TrackerOptions {
  FilterParams filter;  ///< every sensor's filter parameters
  /// With magnetometers (9D: one earth frame for all sensors). false: 6D, each filter has a
  /// heading of its own, aligned at calibration from its site's normal.
  bool use_mag = true;
  /// Calibration capture; heading source mount_normals takes the site normals from the sensors.
  CalibratorOptions calibrator;
  SkeletonOptions skeleton;
  HeadingFromMotionOptions heading_from_motion;  ///< 6D only
};

class BodyTracker {
 public:
  /// Throws std::invalid_argument for a sensor on a segment index out of range.
  BodyTracker(const BodyModel& model, const JointLimits& limits, std::vector<TrackerSensor> sensors,
              TrackerOptions options);

  /// One sample of sensor `i` (its index in the rig). Never allocates.
  void on_sample(int i, const ImuSample& sample);
  /// on_sample in two steps, for a caller that runs the filters of different sensors on other
  /// threads (offline replay: daemon/replay.cpp). filter_sample(i, s) is steps 1-2 for sensor
  /// i alone: it touches nothing but sensor i's filter, so calls for different sensors may run
  /// concurrently, also with track_sample of other samples; it returns the filter's output.
  /// track_sample(i, s, o) is the rest with that output, in sample order on one thread.
  /// on_sample(i, s) == track_sample(i, s, filter_sample(i, s)). Not while capturing(): the
  /// capture's end hands suspected local fields to the filters (they must be in step).
  FilterOutput filter_sample(int i, const ImuSample& sample);
  void track_sample(int i, const ImuSample& sample, const FilterOutput& o);
  /// Starts a capture in `pose`; samples from t_start_ns on are averaged. The result is taken
  /// with take_calibration_result() after the sample that completes it.
  void start_calibration(CalibrationPose pose, int64_t t_start_ns);
  bool capturing() const { return calibrator_.capturing(); }
  double calibration_progress(int64_t t_ns) const { return calibrator_.progress(t_ns); }
  /// The outcome of a capture that finished since the last call (applied when ok).
  std::optional<CalibrationResult> take_calibration_result();

  /// Uses a saved calibration.
  void set_calibration(const Calibration& c) { skeleton_.set_calibration(c); }
  /// Heading-only reset (the person stands facing forward).
  void reset_heading() { skeleton_.reset_heading(); }
  void set_sensor_live(int i, bool live);

  /// The motion-found heading alignment (6D head and feet).
  const HeadingFromMotion& heading_from_motion() const { return heading_; }
  /// The posture at t_ns.
  void solve(int64_t t_ns, PoseFrame& out) { skeleton_.solve(t_ns, out); }

  const Skeleton& skeleton() const { return skeleton_; }
  Skeleton& skeleton() { return skeleton_; }
  const AttitudeFilter& filter(int i) const { return filters_[static_cast<size_t>(i)]; }
  const TrackerSensor& sensor(int i) const { return sensors_[static_cast<size_t>(i)]; }
  int sensor_count() const { return static_cast<int>(sensors_.size()); }
  const TrackerOptions& options() const { return opt_; }
  /// The sensor's health (its filter's state as the tracker uses it, and its calibration).
  SensorHealth sensor_health(int i) const;
  /// The sensor's earth-frame orientation as the tracker uses it (9D or 6D output, or an
  /// orientation source's own).
  Eigen::Quaterniond q_earth_sensor(int i) const;
  /// True once sensor i sent its own orientation instead of rates (its filter stays unused).
  bool orientation_source(int i) const { return is_source_[static_cast<size_t>(i)]; }
  /// Newest sample time seen.
  int64_t newest_t_ns() const { return newest_t_ns_; }

 private:
  std::vector<TrackerSensor> sensors_;
  TrackerOptions opt_;
  std::vector<AttitudeFilter> filters_;
  Skeleton skeleton_;
  Calibrator calibrator_;
  std::optional<CalibrationResult> result_;
  int64_t newest_t_ns_ = 0;
  HeadingFromMotion heading_;
  std::vector<bool> has_mag_;                 ///< per sensor: a magnetometer sample has arrived
  std::vector<bool> is_source_;               ///< per sensor: an orientation source
  std::vector<Eigen::Quaterniond> q_source_;  ///< its newest orientation
  /// Per segment: its sensor's filter has a heading frame of its own (6D, or no magnetometer).
  std::array<bool, kSegmentCount> own_heading_frames() const;
  int64_t heading_applied_t_ns_ = 0;
  /// Per sensor: the previous bias-free rate (sensor frame) and its time, for the angular
  /// acceleration of the joint-centre signal.
  std::vector<Eigen::Vector3d> prev_w_rad_s_;
  std::vector<int64_t> prev_w_t_ns_;
  /// One signal's band-pass state (see feed_heading_from_motion).
  struct BandPass {
    Eigen::Vector3d slow = Eigen::Vector3d::Zero(), fast = Eigen::Vector3d::Zero();
    int64_t t_ns = 0;  ///< 0: no sample yet
  };
  /// Per fitted segment: its own signal's and its reference's band-pass.
  std::array<BandPass, kSegmentCount> own_band_{}, ref_band_{};
  /// Per fitted segment: paired by joint acceleration (else by rate); its joint in the
  /// reference's segment frame from the reference's site, and in its own frame from its own
  /// site along the site normal (the part whose direction in the sensor frame does not depend
  /// on the alignment sought), metres.
  std::array<bool, kSegmentCount> acc_reference_{};
  std::array<Eigen::Vector3d, kSegmentCount> joint_in_reference_m_{}, own_joint_m_{};
  /// Per fitted segment: its first alignment was applied (later ones are rate-limited).
  std::array<bool, kSegmentCount> heading_found_{};
  /// Per segment: aligned from its own site normal and refined from motion within a band, and
  /// how far it has been turned so far, rad.
  std::array<bool, kSegmentCount> refine_{};
  std::array<double, kSegmentCount> turned_rad_{};
  /// q_earth_sensor(i) and sensor_health(i) from the filter's output o.
  Eigen::Quaterniond q_earth_sensor(int i, const FilterOutput& o) const;
  SensorHealth sensor_health(int i, const FilterOutput& o) const;
  void feed_heading_from_motion(int i, const ImuSample& s, const Eigen::Quaterniond& q,
                                const Eigen::Vector3d& gyro_bias_rad_s);
  void start_heading_from_motion(const CalibrationResult& r);
  void apply_heading_from_motion(int64_t t_ns);
  /// Hands the sensors the calibration found off their site normal to their filters.
  void suspect_local_fields(const CalibrationResult& r);
  /// A filter confirmed a local field at calibration and turned its heading by turn_rad.
  void fix_mounting_after_local_field(int seg, double turn_rad);
  /// Per sensor: its filter's local-field fixes last seen.
  std::vector<uint32_t> local_field_fixes_seen_;
  /// Per sensor: its filter's output after its newest sample taken (what sensor_health(i) and
  /// q_earth_sensor(i) report; the filter itself may have run ahead, see filter_sample).
  std::vector<FilterOutput> last_output_;
  /// The sample as the filter takes it: gyro scale divided out, no field in a 6D rig.
  ImuSample prepared(int i, const ImuSample& in) const;
};

/// The rig mapping (segment -> sensor index) of a sensor list.
RigMapping rig_mapping(const std::vector<TrackerSensor>& sensors);

}  // namespace mocap::rig
