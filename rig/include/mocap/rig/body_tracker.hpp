// The body tracker: inertial samples in, a posture out. It owns, in this order per sample:
//   1. the sensor's gyro scale (its one-time table-spin calibration, divided out),
//   2. the sensor's AttitudeFilter (9D, or 6D without magnetometers), or for an orientation
//      source (a sample with q_device_sensor and no gyro, e.g. a SlimeVR tracker) its own
//      orientation (z-up earth frame, heading its own, aligned at calibration like 6D),
//   3. the sensor's orientation as its segment uses it: the filter's 9D or 6D output, or, for a
//      9D sensor whose filter took a local field for north at the calibration, held until the
//      field turns (local_field_watch.hpp),
//   4. the calibration capture (pose_capture.hpp) and, when it completes, the calibration
//      (calibrate.hpp) into the segments' alignment,
//   5. mounting from motion: the mounting motion's window after an N-pose (mounting_motion.hpp)
//      and the knees' hinge axes from any motion (hinge_axis.hpp; a first answer from less
//      evidence for a segment with no facing, or whose site prior it contradicts), each giving
//      facings that replace assumed ones (facing.hpp: replaces; the published pose eases onto one
//      found while tracking, never in one frame: skeleton.hpp); a segment that gets its facing
//      becomes the reference of the fits below it. Not the elbows: a forearm sensor turns with
//      pronation (the forearm segment carries it, skeleton.md), so its axis is not fixed in that
//      sensor's frame; fitted as a hinge it turned the arms 30-140 deg off in 6D after an N-pose
//      alone (24 CMU clips, mean 12.9 deg against 4.4 without); in 6D each knee's two segments'
//      relative heading is then held to its hinge (hinge_heading.hpp), each turning half way,
//      and each thigh's heading to its hip's range (range_heading.hpp: a heading a clipped
//      gyro lost); each pairs the sample with the segment above's orientation only while
//      that one is recent (kPartnerFreshNs: a silent sensor's last one would turn this one),
//   6. in 6D, the heading alignment from motion of the sensors whose facing is still unknown
//      (heading_from_motion.hpp), and by the same fits the headings of the segments whose facing
//      is settled (the mounting motion's, a knee's axes) held to the settled segment above
//      through a long session, the pair following the fit's drift half way each
//      (hold_turn_deg_s); a turn far off a found alignment is refused and counted; a
//      sensor silent for heading_lost_after_s (unless fused on its device: it ran on), or whose
//      device restarted (a sample flagged kFlagDeviceRestarted), lost its heading (marked lost
//      before step 3, and after it turned so that its rotation in the segment above is the one
//      before the gap: keep_joint_above, which finds the head so at once) and is found again here,
//      or by its knee's hinge hold in step 5,
//   7. the skeleton's input (orientation and flags);
// and per frame the skeleton solve (each segment holds its sensor's newest orientation).
//
// Each segment's alignment (mounting and heading, with the source and sigma of each) has one
// owner, the Alignment (alignment.hpp): the calibration, the steps above, a heading reset and a
// saved calibration change it only through its methods, and the skeleton reads the Calibration
// it builds. mocapd, mocap replay, mocap bench accuracy and the tests all run this class; it
// knows no configuration file, clock or thread.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <optional>
#include <vector>

#include "mocap/core/imu_sample.hpp"
#include "mocap/filter/attitude_filter.hpp"
#include "mocap/rig/alignment.hpp"
#include "mocap/rig/calibrate.hpp"
#include "mocap/rig/heading_from_motion.hpp"
#include "mocap/rig/hinge_axis.hpp"
#include "mocap/rig/hinge_heading.hpp"
#include "mocap/rig/local_field_watch.hpp"
#include "mocap/rig/mounting_motion.hpp"
#include "mocap/rig/pose_capture.hpp"
#include "mocap/rig/range_heading.hpp"
#include "mocap/rig/sensor_health.hpp"
#include "mocap/rig/turn_guard.hpp"
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
  /// false: strapped anyhow (no site assumed); its mounting yaw is found from motion.
  bool on_site = true;
  /// Its orientation is computed on the device, which keeps computing it through a silence of
  /// the link and flags its restarts (kFlagDeviceRestarted; drivers' fused_on_device: SlimeVR
  /// over UDP): silence alone does not lose its heading (heading_lost_after_s), a restart does.
  bool fused_on_device = false;
};

struct TrackerOptions {
  FilterParams filter;  ///< every sensor's filter parameters
  /// With magnetometers (9D: one earth frame for all sensors). false: 6D, each filter has a
  /// heading of its own, aligned at calibration from its site's normal.
  bool use_mag = true;
  PoseCaptureOptions capture;
  /// Body-heading source and facings; the site normals are filled from the sensors.
  CalibrationSetup calibration;
  SkeletonOptions skeleton;
  HeadingFromMotionOptions heading_from_motion;  ///< 6D only
  /// Length of the mounting motion's window after its N-pose capture, seconds.
  double mounting_motion_s = 5.0;
  /// A sensor with a heading frame of its own (6D) silent this long lost its heading: its
  /// filter integrates nothing over a gap over kMaxGap_s and a tracker that rebooted starts a new
  /// frame, so whatever the body turned meanwhile is missing. The heading is found again from
  /// motion against its neighbours (step 6), as a heading never known; 0 disables. Seconds.
  double heading_lost_after_s = 1.0;
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
  /// capture's end reads the filters' field norm (they must be in step).
  FilterOutput filter_sample(int i, const ImuSample& sample);
  void track_sample(int i, const ImuSample& sample, const FilterOutput& o);
  /// Starts a capture in `pose`; samples from t_start_ns on are averaged. The result is taken
  /// with take_calibration_result() after the sample that completes it. With mounting_motion
  /// (an N-pose only), the mounting motion follows the capture for options().mounting_motion_s
  /// (mounting_motion.hpp): each segment's facing found from it replaces a less certain one.
  void start_calibration(CalibrationPose pose, int64_t t_start_ns, bool mounting_motion = false);
  /// The mounting motion's window is open.
  bool watching_mounting_motion() const { return mounting_.active(); }
  bool capturing() const { return capturer_.capturing(); }
  double calibration_progress(int64_t t_ns) const { return capturer_.progress(t_ns); }
  /// The outcome of a capture that finished since the last call (applied when ok).
  std::optional<CalibrationResult> take_calibration_result();

  /// Uses a saved calibration.
  void set_calibration(const Calibration& c);
  /// Heading-only reset (the person stands facing forward).
  void reset_heading();
  void set_sensor_live(int i, bool live);

  /// The segments' alignment (mountings and headings with their sources and sigmas).
  const Alignment& alignment() const { return align_; }
  /// The motion-found heading alignment (6D head and feet).
  const HeadingFromMotion& heading_from_motion() const { return heading_; }
  /// The posture at t_ns.
  void solve(int64_t t_ns, PoseFrame& out);

  const Skeleton& skeleton() const { return skeleton_; }
  Skeleton& skeleton() { return skeleton_; }
  const AttitudeFilter& filter(int i) const { return filters_[static_cast<size_t>(i)]; }
  const TrackerSensor& sensor(int i) const { return sensors_[static_cast<size_t>(i)]; }
  int sensor_count() const { return static_cast<int>(sensors_.size()); }
  const TrackerOptions& options() const { return opt_; }
  /// The sensor's health (its filter's state as the tracker uses it, and its calibration).
  SensorHealth sensor_health(int i) const;
  /// The sensor's earth-frame orientation as the tracker uses it (9D or 6D output, held, or an
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
  PoseCapturer capturer_;
  bool mounting_motion_next_ = false;  ///< the capture in progress is followed by the motion
  MountingMotion mounting_;
  Alignment align_;
  uint64_t align_revision_seen_ = 0;
  /// The next published alignment is a new calibration: applied at once, not eased.
  bool snap_alignment_ = false;
  std::optional<CalibrationResult> result_;
  /// The N-pose capture an arm_swing calibration waits to pair with a T-pose.
  std::optional<PoseCapture> npose_;
  int64_t newest_t_ns_ = 0;
  HeadingFromMotion heading_;
  std::vector<bool> has_mag_;                 ///< per sensor: a magnetometer sample has arrived
  std::vector<bool> is_source_;               ///< per sensor: an orientation source
  std::vector<Eigen::Quaterniond> q_source_;  ///< its newest orientation
  std::vector<LocalFieldWatch> field_watch_;  ///< per sensor (9D)
  std::vector<int64_t> prev_t_ns_;            ///< per sensor: its previous sample time
  /// Per segment: its sensor's filter has a heading frame of its own (6D, or no magnetometer).
  std::array<bool, kSegmentCount> own_heading_frames() const;
  int64_t heading_applied_t_ns_ = 0;
  /// Per sensor: its previous sample as the joint-centre signal uses it (the angular
  /// acceleration between the two, every term taken halfway).
  struct PrevMotion {
    Eigen::Vector3d w_rad_s = Eigen::Vector3d::Zero();  ///< bias-free rate, sensor frame
    Eigen::Vector3d acc_m_s2 = Eigen::Vector3d::Zero();
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();  ///< the filter's orientation
    int64_t t_ns = 0;                                       ///< 0: none yet
  };
  std::vector<PrevMotion> prev_motion_;
  /// One signal's band-pass state (see feed_heading_from_motion).
  struct BandPass {
    Eigen::Vector3d slow = Eigen::Vector3d::Zero(), fast = Eigen::Vector3d::Zero();
    int64_t t_ns = 0;  ///< 0: no sample yet
  };
  /// Per fitted segment: its own signal's and its reference's band-pass.
  std::array<BandPass, kSegmentCount> own_band_{}, ref_band_{};
  /// Per fitted segment: paired by joint acceleration (else by rate); its joint in the
  /// reference's segment frame from the reference's site, and in its own frame from its own
  /// site: whole, and along the site normal only (the part whose direction in the sensor frame
  /// does not depend on the alignment sought, used until the first alignment), metres.
  std::array<bool, kSegmentCount> acc_reference_{};
  std::array<Eigen::Vector3d, kSegmentCount> joint_in_reference_m_{}, own_joint_m_{},
      own_joint_along_normal_m_{};
  /// Per fitted segment: its first alignment was applied (later ones are rate-limited).
  std::array<bool, kSegmentCount> heading_found_{};
  /// Per segment: aligned from its own site normal and refined from motion within a band, and
  /// how far it has been turned so far, rad.
  std::array<bool, kSegmentCount> refine_{};
  std::array<double, kSegmentCount> turned_rad_{};
  /// Per segment: its facing settled (a mounting motion's, a knee's axes) and its fit runs on,
  /// its heading following the fit's drift (HeadingFromMotionOptions::hold_turn_deg_s).
  std::array<bool, kSegmentCount> hold_{};
  /// Segment s got a settled facing: its fit from motion holds its heading from now on, or,
  /// with nothing known above it, stops.
  void hold_heading(int s);
  /// A held segment's heading follows its fit's estimate yaw_rad (at the hold's rate).
  void follow_drift(int s, double yaw_rad);
  /// Turns segment s's heading by yaw_rad, its fit and the fits against it told.
  void turn_held(int s, double yaw_rad);
  /// Segment s's own-frame heading is known from more than a site prior (the mounting motion,
  /// a knee's axes, motion) and not lost.
  bool settled(int s) const;
  /// Segment s's sensor lost its own heading frame (heading_lost_after_s): marked lost, fitted
  /// afresh against the nearest known segment above it (or, for the root, a child fitted
  /// against it), its joint holds paused until it is found.
  void lose_heading(int s);
  /// Whether segment s's heading is lost now.
  bool lost(int s) const { return s >= 0 && align_.segment(s).heading_lost; }
  /// Whether sensor i's newest sample is recent at t_ns (kPartnerFreshNs): a joint's
  /// constraints pair a sample only with such a one of the segment above.
  bool recent(int i, int64_t t_ns) const;
  /// Each segment's rotation in the nearest tracked segment above it (`above`), both as
  /// published at the segment's newest sample, while headings can be lost (6D).
  struct JointAbove {
    int above = -1;  ///< -1: none kept
    Eigen::Quaterniond q_above_segment = Eigen::Quaterniond::Identity();
  };
  std::array<JointAbove, kSegmentCount> joint_above_{};
  /// Keeps segment s's JointAbove from its sensor's orientation q (step 3's), where both
  /// segments are aligned and the one above has its heading (none kept across a new calibration
  /// or heading reset). gap_ended: s's heading was just lost (q is its first orientation after
  /// the gap): first turned so that its rotation in the segment above is the one kept before
  /// the gap (a ball joint's changes little in a few seconds; the dropped sensor's filter missed
  /// the whole turn), and that is its fit's prior (HeadingFromMotionOptions::gap_prior); kept
  /// through an untracked segment (the head through the neck: its fit is too weak), it is found
  /// so. Not across a hinge: a knee or elbow flexes through a gap (the forearm after a 3 s
  /// dropout, mean / worst: 6.9 / 15.9 deg without, 8.5 / 39.2 with; the shank is found by its
  /// hinge).
  void keep_joint_above(int s, const Eigen::Quaterniond& q, bool gap_ended);
  /// The lost root's witness: a child whose fit against the root turns the root (the child's
  /// yaw onto it, the other way round), and that child's reference before (-1: none).
  int root_witness_ = -1, witness_prev_ref_ = -1;
  /// Segment s's heading was found again: marked found (no longer refined within a band: its
  /// heading is the one found); the fits against it, whose evidence was taken in its lost
  /// frame, start over; restart_own_fit: its own fit too (found by something else: a hinge, a
  /// reset).
  void found_again(int s, bool restart_own_fit);
  /// The sensor's orientation as its segment uses it (step 3), from the filter's output o.
  Eigen::Quaterniond q_earth_sensor(int i, const FilterOutput& o) const;
  SensorHealth sensor_health(int i, const FilterOutput& o) const;
  /// Step 4: the capture completed; calibrates into the alignment.
  void finish_calibration();
  void feed_heading_from_motion(int i, const ImuSample& s, const Eigen::Quaterniond& q,
                                const Eigen::Vector3d& gyro_bias_rad_s);
  /// Fits the segments whose facing is unknown (and refines those from a site normal).
  void start_heading_from_motion();
  /// Whether segment s's heading is known (shares the earth frame, or has a facing).
  bool heading_known(int s, const std::array<bool, kSegmentCount>& own) const;
  /// Whether segment s's heading is to be fitted from motion: tracked, not known, and the rig
  /// calibrated from the mount normals.
  bool seek_heading(int s, const std::array<bool, kSegmentCount>& own) const;
  /// The nearest segment above s whose heading is known; -1 if none.
  int known_above(int s, const std::array<bool, kSegmentCount>& own) const;
  /// Segment s's fit against `ref`: acceleration pairing or rates, the lever arms.
  void set_up_fit(int s, int ref);
  /// Segment s got its facing: the fits below it that were against a segment further up
  /// start over against the nearest known one above them.
  void refit_against(int s);
  /// Facings found from motion: each replaces a held one where replaces() says so; those of
  /// sensors sharing the earth frame vote on the body heading. ease: found while tracking, the
  /// published pose eases onto it (skeleton.hpp); otherwise (the mounting motion, a step of the
  /// calibration) it is part of a new calibration and applies at once.
  void apply_facings(const std::array<Facing, kSegmentCount>& facing, bool ease);
  /// A hinge's axes: the facings of its two segments.
  struct Hinge;
  void apply_hinge_axes(Hinge& h);
  /// Per knee: its segments and the estimator of its axis.
  struct Hinge {
    int upper, lower;
    HingeAxisEstimator axis;
    HingeHeading heading;
    /// Each segment's facing from the previous early answer (NaN: none since the calibration).
    std::array<double, 2> early_yaw_rad{NAN, NAN};
  };
  /// 6D: the hinge's relative heading held to its axis (hinge_heading.hpp), from a sample of
  /// its lower segment's sensor (orientation q, dt_s since its previous sample).
  void hold_hinge_heading(Hinge& h, const Eigen::Quaterniond& q, double dt_s, int64_t t_ns);
  /// The hinge's hold can act: both segments aligned in frames of their own, the axes known
  /// and on the segments' left axes, at most one of them lost.
  bool hinge_holds(const Hinge& h) const;
  /// Segment s's heading is lost and its knee's hinge hold finds it (else its fit does).
  bool found_by_hinge(int s) const;
  std::array<Hinge, 2> hinges_;
  /// The running estimates' far answers: refused, or a wrong first answer corrected.
  TurnGuard turn_guard_;
  /// Per hip: its thigh and the hold of the thigh's heading to the hip's range.
  struct RangeJoint {
    int child;
    RangeHeading heading;
  };
  /// 6D: the child's heading held to its joint's range (range_heading.hpp), from a sample of
  /// its sensor (orientation q, dt_s since its previous sample).
  void hold_range_heading(RangeJoint& r, const Eigen::Quaterniond& q, double dt_s, int64_t t_ns);
  std::array<RangeJoint, 2> ranges_;
  std::vector<Eigen::Vector3d> w_rad_s_;  ///< per sensor: its newest bias-free rate
  void apply_heading_from_motion(int64_t t_ns);
  /// Hands the sensors the calibration found off the body heading to their field watch.
  void suspect_local_fields(const CalibrationResult& r);
  /// The alignment changed: the skeleton takes its calibration.
  void publish_alignment();
  /// Per sensor: its filter's output after its newest sample taken (what sensor_health(i) and
  /// q_earth_sensor(i) report; the filter itself may have run ahead, see filter_sample).
  std::vector<FilterOutput> last_output_;
  /// The sample as the filter takes it: gyro scale divided out, no field in a 6D rig.
  ImuSample prepared(int i, const ImuSample& in) const;
  /// filter_sample and track_sample on the prepared sample (on_sample prepares it once);
  /// sent_mag: the sensor's own sample carried a field (before a 6D rig dropped it).
  FilterOutput filter_prepared(int i, const ImuSample& s);
  void track_prepared(int i, bool sent_mag, const ImuSample& s, const FilterOutput& o);
};

/// The rig mapping (segment -> sensor index) of a sensor list.
RigMapping rig_mapping(const std::vector<TrackerSensor>& sensors);

}  // namespace mocap::rig
