// BodyTracker: gyro scale -> filter (or the sensor's own orientation) -> the segment's sensor
// orientation -> calibration and alignment -> skeleton, for one rig (see body_tracker.hpp).
#include "mocap/rig/body_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <tuple>

#include "mocap/core/segments.hpp"
#include "mocap/core/units.hpp"
#include "mocap/skeleton/quat_math.hpp"
#include "mocap/skeleton/sensor_sites.hpp"

namespace mocap::rig {
namespace {

/// A knee's heading is held to its hinge only where its segments' mountings put their left
/// axes within 10 deg of the hinge's axes found: held to a hinge its segments' axes do not lie
/// on, the knee would turn away from it.
const double kCosHingeAgree = std::cos(10.0 * kRadPerDeg);

/// A lost heading found by its knee's hinge is found once the hold has followed it for three
/// of its time constants (95 % of the error taken out), counted in horizontal-axis seconds.
const double kHingeFoundAfterS = 3 * HingeHeadingOptions{}.tau_s;
// The headings from motion are applied at 10 Hz: an alignment is a slow constant.
constexpr int64_t kHeadingEveryNs = 100'000'000;
constexpr double kHeadingEveryS = static_cast<double>(kHeadingEveryNs) * 1e-9;

/// The segment above's newest orientation is recent enough for a joint's constraints (ns).
constexpr int64_t kPartnerFreshNs = 250'000'000;
/// An early hinge answer further than this from the one before is not taken: the fit has not
/// settled (CMU 02_03 after an N-pose alone, seeds 6 and 9: a second answer 35 deg from the
/// first and 47 off the right shank's site prior, taken, put the shank 18.5 / 18.6 deg worse
/// than its filter alone over the clip; 0.3 with this; 20 deg gives the same). The real run's
/// first early answers come steady and are taken at once.
constexpr double kEarlySteadyDeg = 10.0;

/// The configured setup with each sensor's site normal filled in (its own, or its segment's
/// standard site; none for a sensor strapped anyhow).
CalibrationSetup calibration_setup(const std::vector<TrackerSensor>& sensors,
                                   const TrackerOptions& o) {
  CalibrationSetup c = o.calibration;
  for (const TrackerSensor& s : sensors) {
    if (s.segment < 0) continue;
    c.site_normal_body[s.segment] =
        !s.on_site ? Eigen::Vector3d::Zero()
        : s.site_normal_body.squaredNorm() > 0
            ? Eigen::Vector3d(s.site_normal_body.normalized())
            : standard_site_normal_body(static_cast<Segment>(s.segment));
  }
  return c;
}

}  // namespace

RigMapping rig_mapping(const std::vector<TrackerSensor>& sensors) {
  RigMapping r = RigMapping::none();
  for (size_t i = 0; i < sensors.size(); ++i) {
    const int seg = sensors[i].segment;
    if (seg >= kSegmentCount)
      throw std::invalid_argument("sensor " + std::to_string(i) + ": no segment " +
                                  std::to_string(seg));
    if (seg >= 0) r.sensor_for_segment[seg] = static_cast<int>(i);
  }
  return r;
}

BodyTracker::BodyTracker(const BodyModel& model, const JointLimits& limits,
                         std::vector<TrackerSensor> sensors, TrackerOptions options)
    : sensors_(std::move(sensors)),
      opt_(std::move(options)),
      filters_(sensors_.size(), AttitudeFilter(opt_.filter)),
      skeleton_(model, limits, rig_mapping(sensors_), opt_.skeleton),
      capturer_(rig_mapping(sensors_), opt_.capture),
      heading_(opt_.heading_from_motion),
      has_mag_(sensors_.size(), false),
      is_source_(sensors_.size(), false),
      q_source_(sensors_.size(), Eigen::Quaterniond::Identity()),
      field_watch_(sensors_.size()),
      prev_t_ns_(sensors_.size(), 0),
      prev_motion_(sensors_.size()),
      hinges_{{{index(Segment::thigh_l), index(Segment::shank_l), HingeAxisEstimator(1),
                HingeHeading{}},
               {index(Segment::thigh_r), index(Segment::shank_r), HingeAxisEstimator(1),
                HingeHeading{}}}},
      ranges_{
          {{index(Segment::thigh_l), RangeHeading{}}, {index(Segment::thigh_r), RangeHeading{}}}},
      w_rad_s_(sensors_.size(), Eigen::Vector3d::Zero()),
      last_output_(sensors_.size(), AttitudeFilter(opt_.filter).output()) {
  opt_.calibration = calibration_setup(sensors_, opt_);
  align_revision_seen_ = align_.revision();
}

Eigen::Quaterniond BodyTracker::q_earth_sensor(int i) const {
  return q_earth_sensor(i, last_output_[static_cast<size_t>(i)]);
}

Eigen::Quaterniond BodyTracker::q_earth_sensor(int i, const FilterOutput& o) const {
  const size_t k = static_cast<size_t>(i);
  if (is_source_[k]) return q_source_[k];
  if (!opt_.use_mag) return o.q_earth_sensor_6d;
  return field_watch_[k].q_earth_sensor(o);
}

SensorHealth BodyTracker::sensor_health(int i) const {
  if (i < 0 || i >= sensor_count()) return SensorHealth{};
  return sensor_health(i, last_output_[static_cast<size_t>(i)]);
}

SensorHealth BodyTracker::sensor_health(int i, const FilterOutput& o) const {
  SensorHealth h;
  h.at_rest = o.flags.at_rest;
  h.mag_disturbed = opt_.use_mag && o.flags.mag_disturbed;
  h.mag_no_reference = opt_.use_mag && o.flags.mag_no_reference;
  h.gyro_bias_rad_s = o.gyro_bias_rad_s.norm();
  h.heading_sigma_rad = opt_.use_mag ? o.heading_sigma_rad : 0.0;
  const int seg = sensors_[static_cast<size_t>(i)].segment;
  h.calibrated = seg >= 0 && align_.segment(seg).aligned;
  return h;
}

void BodyTracker::on_sample(int i, const ImuSample& in) {
  if (i < 0 || i >= sensor_count()) return;
  const ImuSample s = prepared(i, in);
  track_prepared(i, in.has(kFieldMag), s, filter_prepared(i, s));
}

ImuSample BodyTracker::prepared(int i, const ImuSample& in) const {
  // 1. Gyro scale (1 when uncalibrated); a 6D rig ignores any magnetometer.
  ImuSample s = in;
  s.gyr_rad_s = s.gyr_rad_s.cwiseQuotient(sensors_[static_cast<size_t>(i)].gyr_scale);
  if (!opt_.use_mag) s.valid = static_cast<uint8_t>(s.valid & ~kFieldMag);
  return s;
}

FilterOutput BodyTracker::filter_sample(int i, const ImuSample& in) {
  return filter_prepared(i, prepared(i, in));
}

void BodyTracker::track_sample(int i, const ImuSample& in, const FilterOutput& o) {
  if (i < 0 || i >= sensor_count()) return;
  track_prepared(i, in.has(kFieldMag), prepared(i, in), o);
}

FilterOutput BodyTracker::filter_prepared(int i, const ImuSample& s) {
  AttitudeFilter& f = filters_[static_cast<size_t>(i)];
  // 2. Filter; an orientation source (a tracker running its own filter, sending its
  //    orientation without rates: kFieldQuat and no gyro) stands in for it (track_prepared).
  if (!(s.has(kFieldQuat) && !s.has(kFieldGyr))) f.update(s);
  return f.output();
}

void BodyTracker::track_prepared(int i, bool sent_mag, const ImuSample& s, const FilterOutput& o) {
  const size_t k = static_cast<size_t>(i);
  const TrackerSensor& sensor = sensors_[k];
  if (sent_mag) has_mag_[k] = true;
  if (s.has(kFieldQuat) && !s.has(kFieldGyr)) {
    q_source_[k] = s.q_device_sensor;
    is_source_[k] = true;
  }
  last_output_[k] = o;
  newest_t_ns_ = std::max(newest_t_ns_, s.t_host_ns);
  const double dt_s =
      prev_t_ns_[k] != 0 ? static_cast<double>(s.t_host_ns - prev_t_ns_[k]) * 1e-9 : 0.0;
  prev_t_ns_[k] = s.t_host_ns;
  const int seg = sensor.segment;
  if (seg < 0) return;
  // A heading of its own is lost in a silence (but not by a device that computes its
  // orientation itself: it ran on) and at a restart of the device.
  const bool own_headings = heading_.active();
  const bool silence_loses = opt_.heading_lost_after_s > 0 && !sensor.fused_on_device;
  const bool was_lost = lost(seg);
  if (own_headings &&
      ((silence_loses && dt_s > opt_.heading_lost_after_s) || (s.flags & kFlagDeviceRestarted)))
    lose_heading(seg);  // found again in step 6
  // 3. The sensor's orientation as its segment uses it; a watched local field may turn the
  //    mounting once it turns (and the held heading with it, or let it go: no motion, so the
  //    published segment is eased onto it in step 7, as an alignment found while tracking).
  LocalFieldWatch& watch = field_watch_[k];
  Eigen::Quaterniond q_held = Eigen::Quaterniond::Identity();
  const bool held = watch.holding();
  if (held) {
    q_held = q_earth_sensor(i, o);
    double turned_rad = 0;
    if (s.has(kFieldMag) && watch.on_field(o, dt_s, turned_rad))
      align_.turn_mounting(seg, turned_rad, AlignSource::local_field);
    watch.on_sample(o, dt_s);
  }
  const Eigen::Quaterniond q = q_earth_sensor(i, o);
  if (own_headings) keep_joint_above(seg, q, lost(seg) && !was_lost);
  // 4. Calibration capture; when it completes, the calibration.
  if (capturer_.capturing()) {
    capturer_.add_sample(seg, q, s.t_host_ns, s.has(kFieldAcc) ? &s.acc_m_s2 : nullptr);
    if (capturer_.done(s.t_host_ns)) finish_calibration();
  }
  // 5. Mounting from motion: the mounting motion's window, the knees' axes.
  if (mounting_.active()) {
    mounting_.add(seg, q, s.t_host_ns);
    if (mounting_.done(s.t_host_ns)) apply_facings(mounting_.finish(), false);
  }
  if (s.has(kFieldGyr)) w_rad_s_[k] = s.gyr_rad_s - o.gyro_bias_rad_s;
  const RigMapping& rig = skeleton_.rig();
  for (Hinge& h : hinges_) {
    if (h.lower != seg || !rig.tracked(h.upper) || !s.has(kFieldGyr)) continue;
    const int up = rig.sensor_for_segment[h.upper];
    if (!recent(up, s.t_host_ns)) continue;
    h.axis.add(q_earth_sensor(up), q, w_rad_s_[static_cast<size_t>(up)], w_rad_s_[k], s.t_host_ns);
    if (h.axis.updated()) apply_hinge_axes(h);
    hold_hinge_heading(h, q, dt_s, s.t_host_ns);
  }
  for (RangeJoint& r : ranges_)
    if (r.child == seg) hold_range_heading(r, q, dt_s, s.t_host_ns);
  // 6. 6D: the heading of the sensors whose facing is still unknown, from motion.
  if (heading_.active() && s.has(kFieldGyr) && s.has(kFieldAcc)) {
    feed_heading_from_motion(i, s, q, o.gyro_bias_rad_s);
    apply_heading_from_motion(s.t_host_ns);
  }
  publish_alignment();
  // 7. The segment's input: orientation and the filter's flags.
  if (held && q_held.angularDistance(q) > 0) {
    const Calibration& c = align_.calibration();
    skeleton_.ease_segment(seg, c.segment_from_sensor(seg, q_held), c.segment_from_sensor(seg, q));
  }
  skeleton_.set_sensor_orientation(seg, q, s.t_host_ns, sensor_health(i, o).segment_flags());
}

void BodyTracker::publish_alignment() {
  if (align_.revision() == align_revision_seen_) return;
  align_revision_seen_ = align_.revision();
  // A new calibration (or a heading reset) applies at once; an alignment found while tracking
  // is eased into the published pose (skeleton.hpp).
  skeleton_.set_calibration(align_.calibration(), !snap_alignment_);
  snap_alignment_ = false;
}

void BodyTracker::finish_calibration() {
  const PoseCapturer::Result captured = capturer_.finish();
  const bool arm_swing = opt_.calibration.heading == HeadingSource::arm_swing;
  const bool tpose = captured.capture.pose == CalibrationPose::tpose;
  const PoseCapture* npose = arm_swing && tpose && npose_ ? &*npose_ : nullptr;
  Alignment next = align_;
  result_ = calibrate(captured, opt_.calibration, own_heading_frames(), npose, next);
  if (result_->status == CalibrationStatus::need_tpose) npose_ = captured.capture;
  if (!result_->ok()) return;
  npose_.reset();
  align_ = next;
  snap_alignment_ = true;
  turn_guard_.reset();
  joint_above_.fill({});  // kept under the old alignment
  for (LocalFieldWatch& w : field_watch_)
    w = LocalFieldWatch{};
  suspect_local_fields(*result_);
  start_heading_from_motion();
  if (mounting_motion_next_ && captured.capture.pose == CalibrationPose::npose)
    mounting_.start(captured.capture, captured.capture.t_end_ns, opt_.mounting_motion_s);
  // The hinges are straight in the pose: their angles count from here, their axes were
  // horizontal (both segments hang vertical); the holds start over.
  const PoseCapture& c = captured.capture;
  for (Hinge& h : hinges_) {
    h.axis.reset(c.pose == CalibrationPose::npose ? c.t_end_ns : 0);
    if (c.pose == CalibrationPose::npose && c.have[h.upper] && c.have[h.lower])
      h.axis.set_pose_up(c.up_sensor(h.upper), c.up_sensor(h.lower));
    h.heading.reset();
    h.early_yaw_rad = {NAN, NAN};
  }
  for (RangeJoint& r : ranges_)
    r.heading.reset();
}

void BodyTracker::apply_hinge_axes(Hinge& h) {
  const HingeAxisEstimator& est = h.axis;
  const int upper = h.upper, lower = h.lower;
  // A real knee's axis is within a few degrees of the segment's lateral axis; the sign of each
  // axis must be clear, and no other choice of signs nearly as good (a wrong sign turns the
  // segment 180 deg, then held by the rejection of far turns).
  constexpr double kModelSigmaDeg = 5.0;
  if (!align_.has_capture() || !est.signs_sure()) return;
  std::array<Facing, kSegmentCount> f{};
  const PoseCapture& c = align_.capture();
  const double sigma = est.sigma_deg();
  for (int side = 0; side < 2; ++side) {
    const int s = side == 0 ? upper : lower;
    // The axis points to the left (+y); forward is y x z.
    const Eigen::Vector3d forward = (side == 0 ? est.axis1() : est.axis2()).cross(c.up_sensor(s));
    if (forward.norm() < 0.5) continue;  // the axis near the segment's long axis: no yaw in it
    f[s] =
        facing_from_axis(c, s, forward, std::hypot(kModelSigmaDeg, sigma), AlignSource::hinge_axis);
    if (est.full_evidence() || !f[s].known()) continue;
    // An early answer (less evidence) only for a segment with no facing at all, or one whose
    // assumed facing it contradicts (hinge_axis.hpp: kEarlyEvidence), and only while steady:
    // the first, or within kEarlySteadyDeg of the one before.
    const Facing& held = align_.segment(s).facing;
    double& previous = h.early_yaw_rad[static_cast<size_t>(side)];
    const bool steady = std::isnan(previous) || std::abs(wrap_angle_rad(f[s].yaw_rad - previous)) <
                                                    kEarlySteadyDeg * kRadPerDeg;
    previous = f[s].yaw_rad;
    if (!steady || (held.known() && !contradicts(held, f[s]))) f[s] = Facing{};
  }
  apply_facings(f, true);
}

bool BodyTracker::hinge_holds(const Hinge& h) const {
  const SegmentAlignment &au = align_.segment(h.upper), &al = align_.segment(h.lower);
  if (!au.aligned || !al.aligned || !au.own_frame || !al.own_frame || !h.axis.known() ||
      (au.heading_lost && al.heading_lost))
    return false;
  // Only where the segments' left axes are the hinge's axes (kCosHingeAgree).
  const Calibration& c = align_.calibration();
  return std::abs((c.q_sensor_segment[h.upper] * Eigen::Vector3d::UnitY()).dot(h.axis.axis1())) >=
             kCosHingeAgree &&
         std::abs((c.q_sensor_segment[h.lower] * Eigen::Vector3d::UnitY()).dot(h.axis.axis2())) >=
             kCosHingeAgree;
}

bool BodyTracker::found_by_hinge(int s) const {
  for (const Hinge& h : hinges_)
    if ((h.upper == s || h.lower == s) && lost(s) && hinge_holds(h)) return true;
  return false;
}

// A joint's constraints pair a sample with the segment above's newest only while that one is
// recent: a silent sensor's last orientation would turn this one (a thigh silent 3 s while its
// device's fusion ran on, CMU 6D seed 1: its joint after 12.5 deg mean, 10.5 lost and found
// again, 8.7 so).
bool BodyTracker::recent(int i, int64_t t_ns) const {
  return t_ns - prev_t_ns_[static_cast<size_t>(i)] <= kPartnerFreshNs;
}

void BodyTracker::hold_hinge_heading(Hinge& h, const Eigen::Quaterniond& q, double dt_s,
                                     int64_t t_ns) {
  if (!hinge_holds(h)) return;
  const SegmentAlignment &au = align_.segment(h.upper), &al = align_.segment(h.lower);
  const Calibration& c = align_.calibration();
  const int up = skeleton_.rig().sensor_for_segment[h.upper];
  // A lost heading of either segment is found by the hinge: followed whatever its error, by
  // that segment alone, for kHingeFoundAfterS.
  const int lost_seg = au.heading_lost ? h.upper : al.heading_lost ? h.lower : -1;
  h.heading.add(c.segment_from_sensor(h.upper, q_earth_sensor(up)) * Eigen::Vector3d::UnitY(),
                c.segment_from_sensor(h.lower, q) * Eigen::Vector3d::UnitY(), dt_s, lost_seg < 0);
  if (!h.heading.due(t_ns)) return;
  if (lost_seg >= 0) {
    const double yaw = h.heading.take();
    align_.turn_heading(lost_seg, lost_seg == h.lower ? yaw : -yaw, AlignSource::joint,
                        align_.segment(lost_seg).heading_sigma_deg);
    if (h.heading.followed_s() >= kHingeFoundAfterS) found_again(lost_seg, true);
    return;
  }
  if (h.heading.take_refused() > 0) align_.reject_turn(h.lower);
  // Neither segment's 6D frame is known better than the other's: each turns half way (CMU 6D,
  // 24 clips x 3 seeds: turning the shank alone onto the thigh took a thigh's drift into the
  // shank, worst segment excess 2.4 -> 7.1 deg; half way with the hips' range holds 2.9).
  const double yaw = h.heading.take();
  if (yaw == 0) return;
  align_.turn_heading(h.lower, 0.5 * yaw, AlignSource::joint, al.heading_sigma_deg);
  align_.turn_heading(h.upper, -0.5 * yaw, AlignSource::joint, au.heading_sigma_deg);
}

void BodyTracker::hold_range_heading(RangeJoint& r, const Eigen::Quaterniond& q, double dt_s,
                                     int64_t t_ns) {
  const int parent = kSegmentParent[r.child];
  const SegmentAlignment &ac = align_.segment(r.child), &ap = align_.segment(parent);
  if (!ac.aligned || !ap.aligned || !ac.own_frame || ac.heading_lost || ap.heading_lost) return;
  const Calibration& c = align_.calibration();
  const int up = skeleton_.rig().sensor_for_segment[parent];
  if (up < 0 || !recent(up, t_ns)) return;
  r.heading.add(skeleton_.limits().joint[r.child],
                c.segment_from_sensor(parent, q_earth_sensor(up)),
                c.segment_from_sensor(r.child, q), dt_s);
  if (!r.heading.due(t_ns)) return;
  const double yaw = r.heading.take();
  if (yaw != 0) align_.turn_heading(r.child, yaw, AlignSource::joint, ac.heading_sigma_deg);
}

void BodyTracker::apply_facings(const std::array<Facing, kSegmentCount>& facing, bool ease) {
  if (!ease) snap_alignment_ = true;
  std::array<bool, kSegmentCount> shared{};
  AlignSource source = AlignSource::none;
  for (int s = 0; s < kSegmentCount; ++s) {
    const SegmentAlignment& a = align_.segment(s);
    if (!facing[s].known() || !a.aligned) continue;
    // A running estimate's answer far off the facing it found is refused, not followed (a
    // segment never flips), unless it corrects a wrong first answer (turn_guard.hpp).
    const Facing& held = a.facing;
    const TurnGuard::Verdict v = turn_guard_.judge(s, held, facing[s]);
    if (v == TurnGuard::Verdict::refuse) {
      align_.reject_turn(s);
      continue;
    }
    if (v == TurnGuard::Verdict::correct) align_.correct_turn(s);
    if (v == TurnGuard::Verdict::correct || replaces(held, facing[s])) {
      const bool was_known = a.facing.known();
      align_.set_facing(s, facing[s]);
      hold_heading(s);
      if (!was_known) refit_against(s);
    }
    shared[s] = !a.own_frame;
    source = facing[s].source;
  }
  // The body heading from the sensors sharing the earth frame, where it replaces the one used.
  const BodyHeading b = body_heading_from_facings(facing, shared);
  double sigma_deg = 180;
  for (int s = 0; s < kSegmentCount; ++s)
    if (b.agreed[s]) sigma_deg = std::min(sigma_deg, facing[s].sigma_deg);
  // The body heading turns every mounting: it changes only where none was known or once from
  // the mounting motion (a calibration step), never by the running updates of an estimate.
  const Facing held{align_.body_heading_rad(), align_.body_heading_sigma_deg(),
                    align_.body_heading_source()};
  const bool first_motion = source == AlignSource::motion && held.source != AlignSource::motion &&
                            sigma_deg < held.sigma_deg;
  if (b.heading_rad && held.source != source && (!held.known() || first_motion)) {
    align_.set_body_heading(*b.heading_rad, source, sigma_deg);
    // A sensor whose motion agrees with the body heading was not in a local field: its site
    // prior was off (not on its site, or the pose turned there).
    for (size_t k = 0; k < sensors_.size(); ++k) {
      const int sg = sensors_[k].segment;
      if (sg >= 0 && b.agreed[sg]) field_watch_[k] = LocalFieldWatch{};
    }
  }
}

void BodyTracker::solve(int64_t t_ns, PoseFrame& out) {
  skeleton_.solve(t_ns, out);
}

void BodyTracker::set_calibration(const Calibration& c) {
  align_.load(c);
  snap_alignment_ = true;
  turn_guard_.reset();
  joint_above_.fill({});
  publish_alignment();
}

void BodyTracker::reset_heading() {
  std::array<Eigen::Quaterniond, kSegmentCount> q_es;
  std::array<bool, kSegmentCount> have{};
  for (int s = 0; s < kSegmentCount; ++s) {
    q_es[s] = skeleton_.sensor_orientation(s);
    have[s] = skeleton_.sensor_live(s);
  }
  align_.reset_heading(q_es, have);
  joint_above_.fill({});
  // A reset answers a lost heading.
  for (int s = 0; s < kSegmentCount; ++s)
    if (have[s] && lost(s)) found_again(s, true);
  snap_alignment_ = true;
  publish_alignment();
}

void BodyTracker::feed_heading_from_motion(int i, const ImuSample& s, const Eigen::Quaterniond& q,
                                           const Eigen::Vector3d& gyro_bias_rad_s) {
  constexpr double kHighPassTauS = 1.0;  // slower than a step, faster than a tilt error's drift
  // About 3 Hz (CMU 6D, 24 clips x 3 seeds, worst foot excess on random straps: 0.03 s 4.8,
  // 0.05 s 2.3 deg; before the timing below was fixed, 0.01 s let the differentiated rate's
  // jitter in: 23.6 deg).
  constexpr double kLowPassTauS = 0.05;
  constexpr double kGravity_m_s2 = 9.81;
  const size_t k = static_cast<size_t>(i);
  const int seg = sensors_[k].segment;
  const Calibration& c = align_.calibration();
  const Eigen::Vector3d w = s.gyr_rad_s - gyro_bias_rad_s;
  PrevMotion& prev = prev_motion_[k];
  const double dt_s = static_cast<double>(s.t_host_ns - prev.t_ns) * 1e-9;
  const bool have_dw = prev.t_ns != 0 && dt_s > 0 && dt_s < 0.05;
  const PrevMotion before = prev;
  prev = {w, s.acc_m_s2, q, s.t_host_ns};
  if (!have_dw) return;
  // The rotation terms use the rate's difference, which belongs between the two samples: every
  // term is taken there (mean rate, mean specific force, halfway orientation). Taken at the
  // newer sample they lag the angular acceleration by half a sample, and the fit turns with the
  // motion (CMU 6D: left foot mean excess 0.80 -> 0.16 deg).
  const Eigen::Vector3d dw = (w - before.w_rad_s) / dt_s;
  const Eigen::Vector3d w_mid = 0.5 * (w + before.w_rad_s);
  const Eigen::Vector3d acc_mid_m_s2 = 0.5 * (s.acc_m_s2 + before.acc_m_s2);
  const Eigen::Quaterniond q_mid = before.q.slerp(0.5, q);
  const Eigen::Quaterniond q_aligned = c.q_correction[seg] * q_mid;
  // Acceleration (gravity removed, aligned earth frame) of the point r_seg of the segment's
  // frame from its sensor: the sensor's specific force plus the rotation terms.
  const auto acc_at = [&](const Eigen::Vector3d& r_seg) -> Eigen::Vector3d {
    const Eigen::Vector3d r = c.q_sensor_segment[seg] * r_seg;
    const Eigen::Vector3d a = acc_mid_m_s2 + dw.cross(r) + w_mid.cross(w_mid.cross(r));
    return q_aligned * a - Eigen::Vector3d(0, 0, kGravity_m_s2);
  };
  // The same band-pass for both signals of a pair (it commutes with the yaw sought): the
  // high-pass removes each filter's slow gravity leak, the low-pass the jitter above a few Hz
  // (skin, the rotation terms' differentiated rate) that carries no joint motion.
  const auto band_pass = [&](const Eigen::Vector3d& v, BandPass& f) {
    if (f.t_ns == 0) {
      f.slow = v;
      f.fast = v;
    } else {
      const double step_s = static_cast<double>(s.t_host_ns - f.t_ns) * 1e-9;
      f.slow += std::clamp(step_s / kHighPassTauS, 0.0, 1.0) * (v - f.slow);
      f.fast += std::clamp(step_s / kLowPassTauS, 0.0, 1.0) * (v - f.fast);
    }
    f.t_ns = s.t_host_ns;
    return Eigen::Vector3d(f.fast - f.slow);
  };
  // As a fitted segment: the acceleration of its own joint (its origin) from its sensor, with
  // the rotation terms of the whole lever arm once the segment's first alignment is applied (on
  // the four CMU clips whose feet trail most, x 3 seeds, mean 1.69 -> 1.63 deg), before that of
  // its part along the site normal only (its direction in the sensor frame does not depend on
  // the alignment sought); the rate when acc_reference_ is false. A refined segment counts as
  // aligned only after its first turn beyond the dead band (taking the whole lever arm from
  // its N-pose on moves 32 of 72 CMU 6D runs, the mean not at 4 decimals: 1.0328).
  if (heading_.reference(seg) >= 0) {
    if (acc_reference_[seg])
      heading_.add(seg,
                   band_pass(acc_at(heading_found_[seg] ? own_joint_m_[seg]
                                                        : own_joint_along_normal_m_[seg]),
                             own_band_[seg]),
                   s.t_host_ns);
    else
      heading_.add(seg, q_aligned * w, s.t_host_ns);
  }
  // As a reference: the acceleration of that joint from this sensor (site from
  // skeleton/sensor_sites.hpp, joint through any untracked segment between, held in its
  // calibration pose), or its rate.
  for (int child = 0; child < kSegmentCount; ++child) {
    if (heading_.reference(child) != seg) continue;
    if (acc_reference_[child])
      heading_.add_reference(
          child, band_pass(acc_at(joint_in_reference_m_[child]), ref_band_[child]), s.t_host_ns);
    else
      heading_.add_reference(child, q_aligned * w, s.t_host_ns);
  }
}

std::array<bool, kSegmentCount> BodyTracker::own_heading_frames() const {
  std::array<bool, kSegmentCount> own{};
  for (int i = 0; i < sensor_count(); ++i) {
    const int seg = sensors_[static_cast<size_t>(i)].segment;
    if (seg >= 0) own[seg] = !opt_.use_mag || !has_mag_[static_cast<size_t>(i)];
  }
  return own;
}

bool BodyTracker::heading_known(int s, const std::array<bool, kSegmentCount>& own) const {
  // Known when its sensor shares the earth frame (magnetometer) or was aligned from its own
  // facing.
  return skeleton_.rig().tracked(s) &&
         (!own[s] || (align_.segment(s).facing.known() && !align_.segment(s).heading_lost));
}

bool BodyTracker::seek_heading(int s, const std::array<bool, kSegmentCount>& own) const {
  return opt_.calibration.heading == HeadingSource::mount_normals && skeleton_.rig().tracked(s) &&
         !heading_known(s, own);
}

int BodyTracker::known_above(int s, const std::array<bool, kSegmentCount>& own) const {
  int p = kSegmentParent[s];
  while (p >= 0 && !heading_known(p, own))
    p = kSegmentParent[p];
  return p;
}

void BodyTracker::start_heading_from_motion() {
  std::array<int, kSegmentCount> reference;
  reference.fill(-1);
  const std::array<bool, kSegmentCount> own = own_heading_frames();
  // The segments whose heading is not known are fitted to the nearest known one above.
  for (int s = 0; s < kSegmentCount; ++s)
    if (seek_heading(s, own)) reference[s] = known_above(s, own);
  // Segments aligned from their own horizontal site normal are refined against the same
  // evidence, within a band (a strap tilted off the normal turns that alignment). The upper
  // arms too, though the shoulder girdle moves on the torso, which the model holds rigid (the
  // shoulder's acceleration from the torso's sensor is off by that): CMU 6D after an N-pose
  // alone, 24 clips, seeds 1-3 / 4-10, 1.220 / 1.299 -> 1.107 / 1.193 x the ideally aligned
  // filters, worst segment excess 9.9 / 17.6 -> 6.3 / 10.7 deg (the upper arms' mean excess
  // 1.9 / 1.6 -> 0.4 / 0.3; the forearms' fits are against them: 2.6 / 2.2 -> 1.1 / 1.1).
  refine_.fill(false);
  hold_.fill(false);
  turned_rad_.fill(0);
  root_witness_ = witness_prev_ref_ = -1;
  if (opt_.heading_from_motion.refine_max_deg > 0 &&
      opt_.calibration.heading == HeadingSource::mount_normals)
    for (int s = 0; s < kSegmentCount; ++s) {
      if (!heading_known(s, own) || !own[s] ||
          align_.segment(s).facing.source != AlignSource::site_normal)
        continue;
      reference[s] = known_above(s, own);
      refine_[s] = reference[s] >= 0;
    }
  heading_.reset(reference);
  for (int s = 0; s < kSegmentCount; ++s)
    set_up_fit(s, reference[s]);
  heading_found_ = refine_;  // a refined segment starts aligned
}

void BodyTracker::set_up_fit(int s, int ref) {
  // Joint accelerations pair a segment with its parent or, through the neck (never tracked,
  // short and stiff: held in its calibration pose), the head with the torso; further up (a
  // foot under an untracked shank) the knee's own motion would dominate: rates instead.
  acc_reference_[s] = false;
  own_band_[s] = {};
  ref_band_[s] = {};
  const int p = kSegmentParent[s];
  if (ref < 0 || p < 0) return;
  if (ref != p && !(p == index(Segment::neck) && ref == kSegmentParent[p])) return;
  acc_reference_[s] = true;
  const CalibrationPose pose = align_.calibration().pose;
  const BodyModel& model = skeleton_.model();
  // The joint (s's origin) in the reference's frame.
  Eigen::Vector3d joint_m = model.joint_offset_m(s);
  if (ref != p)
    joint_m = model.joint_offset_m(p) + q_body_segment_in_pose(pose, ref).conjugate() *
                                            (q_body_segment_in_pose(pose, p) * joint_m);
  const Eigen::Vector3d site_m =
      standard_site_position_m(static_cast<Segment>(s), model.dimensions());
  const Eigen::Vector3d n = standard_site_normal_body(static_cast<Segment>(s));
  own_joint_m_[s] = -site_m;
  own_joint_along_normal_m_[s] = -n.dot(site_m) * n;
  joint_in_reference_m_[s] =
      joint_m - standard_site_position_m(static_cast<Segment>(ref), model.dimensions());
}

bool BodyTracker::settled(int s) const {
  const SegmentAlignment& a = align_.segment(s);
  return a.aligned && a.own_frame && !a.heading_lost && a.facing.known() &&
         a.facing.source != AlignSource::site_normal;
}

void BodyTracker::hold_heading(int s) {
  refine_[s] = hold_[s] = false;
  // Held against a site prior, a segment would take on that prior's error (CMU 6D after an
  // N-pose alone, a 10 min session: 8.41 -> 9.46 deg; the thighs against the pelvis).
  const int ref = known_above(s, own_heading_frames());
  if (!heading_.active() || opt_.heading_from_motion.hold_turn_deg_s <= 0 ||
      !align_.segment(s).own_frame || ref < 0 || !settled(ref)) {
    heading_.stop(s);  // its heading follows the facing now, not a fit
    return;
  }
  heading_.restart(s, ref);
  set_up_fit(s, ref);
  hold_[s] = heading_found_[s] = true;
}

void BodyTracker::refit_against(int s) {
  // Segment s got its facing: each fit below it against a segment further up (s was not
  // known), or not yet fitted for want of any known segment above (random straps: the pelvis,
  // thigh and shank facings found by the mounting motion, the foot's heading then never sought:
  // CMU 6D seed 5, foot_l 20-86 deg worse than its filter alone on every clip), starts over
  // against the nearest known segment above it now, s or below, and its first new estimate
  // aligns it. (A known reference's facing that moves does not restart the fits against it:
  // they follow at the drift limit; restarting made the first estimate after each hinge update
  // count, from little evidence.)
  const std::array<bool, kSegmentCount> own = own_heading_frames();
  for (int t = 0; t < kSegmentCount; ++t) {
    const int ref = heading_.reference(t);
    if (t == s || (ref < 0 && !seek_heading(t, own)) || refine_[t]) continue;
    bool below = false;
    for (int p = kSegmentParent[t]; p >= 0 && !below; p = kSegmentParent[p])
      below = p == s;
    if (!below) continue;
    const int next = known_above(t, own);
    if (next == ref) continue;
    heading_.restart(t, next);
    set_up_fit(t, next);
    heading_found_[t] = false;
  }
}

void BodyTracker::lose_heading(int s) {
  const SegmentAlignment& a = align_.segment(s);
  if (!a.aligned || !a.own_frame || a.heading_lost) return;
  align_.lose_heading(s);
  refine_[s] = hold_[s] = false;
  turned_rad_[s] = 0;
  heading_found_[s] = false;
  const int ref = known_above(s, own_heading_frames());
  heading_.restart(s, ref);
  set_up_fit(s, ref);
  // The root has nothing above it: a child's fit against it witnesses its heading.
  if (ref < 0 && kSegmentParent[s] < 0 && root_witness_ < 0) {
    const std::array<bool, kSegmentCount> own = own_heading_frames();
    for (int c = 0; c < kSegmentCount && root_witness_ < 0; ++c)
      if (kSegmentParent[c] == s && heading_known(c, own)) {
        root_witness_ = c;
        witness_prev_ref_ = heading_.reference(c);
        heading_.restart(c, s);
        set_up_fit(c, s);
      }
  }
  // Its joints' holds start over; they wait while it is lost (hold_hinge_heading,
  // hold_range_heading).
  for (Hinge& h : hinges_)
    if (h.upper == s || h.lower == s) h.heading.reset();
  for (RangeJoint& r : ranges_)
    if (r.child == s || kSegmentParent[r.child] == s) r.heading.reset();
}

void BodyTracker::keep_joint_above(int s, const Eigen::Quaterniond& q, bool gap_ended) {
  const RigMapping& rig = skeleton_.rig();
  int above = kSegmentParent[s];
  while (above >= 0 && !rig.tracked(above))
    above = kSegmentParent[above];
  JointAbove& j = joint_above_[s];
  if (above < 0 || lost(above) || !align_.segment(s).aligned || !align_.segment(above).aligned) {
    j.above = -1;
    return;
  }
  const Calibration& c = align_.calibration();
  const Eigen::Quaterniond q_above =
      c.segment_from_sensor(above, q_earth_sensor(rig.sensor_for_segment[above]));
  if (gap_ended && j.above == above && !is_hinge(static_cast<Segment>(s))) {
    // The turn about the vertical from where the segment is now to where the kept joint puts
    // it (the filter's tilt is its own after the gap; the heading is what it missed).
    const Eigen::Quaterniond d =
        q_above * j.q_above_segment * c.segment_from_sensor(s, q).conjugate();
    const double yaw_rad = wrap_angle_rad(2 * std::atan2(d.z(), d.w()));
    if (std::isfinite(yaw_rad)) {
      align_.turn_heading(s, yaw_rad, AlignSource::joint, align_.segment(s).heading_sigma_deg);
      // Kept through an untracked segment (the head through the neck), where the fit is too
      // weak to find it (CMU 6D, head dropped 3 s, 17 clips x seeds 1-3, joint error from 5 s
      // after: mean 31.6-32.8, worst 59.9-77.3 deg found by the fit; 28.7-29.4 / 46.4-46.7
      // found at once; a prior 3 or 6 times as strong 28.6-29.5 / 46.3-46.4): found at once.
      // Elsewhere the kept joint is the fit's prior.
      if (kSegmentParent[s] != above)
        found_again(s, true);
      else
        heading_.seed(s, opt_.heading_from_motion.gap_prior);
    }
  }
  j = {above, q_above.conjugate() * c.segment_from_sensor(s, q)};
}

void BodyTracker::found_again(int s, bool restart_own_fit) {
  if (restart_own_fit) heading_.restart(s, heading_.reference(s));
  align_.regain_heading(s);
  heading_found_[s] = true;
  for (int t = 0; t < kSegmentCount; ++t) {
    if (t == s || heading_.reference(t) != s) continue;
    const int ref = t == root_witness_ ? witness_prev_ref_ : s;
    heading_.restart(t, ref);
    set_up_fit(t, ref);
  }
  if (kSegmentParent[s] < 0) root_witness_ = witness_prev_ref_ = -1;
}

void BodyTracker::apply_heading_from_motion(int64_t t_ns) {
  constexpr double kMinTurnRad = 0.1 * kRadPerDeg;
  if (t_ns - heading_applied_t_ns_ < kHeadingEveryNs) return;
  const double max_turn_rad =
      opt_.heading_from_motion.max_drift_deg_s * kRadPerDeg * kHeadingEveryS;
  heading_applied_t_ns_ = t_ns;
  const double dead_band_rad = opt_.heading_from_motion.refine_dead_band_deg * kRadPerDeg;
  const double refine_max_rad = opt_.heading_from_motion.refine_max_deg * kRadPerDeg;
  for (int s = 0; s < kSegmentCount; ++s) {
    double yaw = 0;
    const int ref = heading_.reference(s);
    // A fit against a lost segment waits for it, unless it witnesses the lost root: its first
    // estimate turns the root (the other way), which is then found.
    const bool witness = s == root_witness_ && lost(ref);
    if (lost(ref) && !witness) continue;
    // A lost heading is kept as the best guess until the fit has settled, then follows the
    // fit whole until it is found (found_evidence): a first estimate from little evidence,
    // applied at once and then held to the drift limit, locked on wrong (CMU 01_08: the
    // forearm's first estimate 150 deg, the evidence after it 99 deg more, refused).
    const int lost_seg = witness ? ref : lost(s) ? s : -1;
    if (lost_seg >= 0 && found_by_hinge(lost_seg)) continue;  // its hinge finds it
    if (lost_seg >= 0) {
      const double evidence = heading_.evidence(s);
      if (evidence < opt_.heading_from_motion.settle_evidence || !heading_.estimate(s, yaw))
        continue;
      align_.turn_heading(lost_seg, witness ? -yaw : yaw, AlignSource::joint,
                          align_.segment(lost_seg).heading_sigma_deg);
      heading_.applied(s, yaw);
      if (evidence >= opt_.heading_from_motion.found_evidence) found_again(lost_seg, false);
      continue;
    }
    if (!heading_.estimate(s, yaw)) continue;
    if (std::abs(yaw) < kMinTurnRad) continue;
    if (hold_[s]) {
      follow_drift(s, yaw);
      continue;
    }
    // A refined segment moves only when the evidence is off by more than the fit's own bias
    // (model mismatch: joint centres, carrying angle), and stays within its band.
    if (refine_[s]) {
      if (std::abs(yaw) <= dead_band_rad) continue;
      yaw -= std::copysign(dead_band_rad, yaw);
    }
    // The first estimate aligns; afterwards the alignment only follows the slow drift of the
    // 6D heading, so a stretch of misleading motion cannot turn it over, and evidence far off a
    // found alignment (a flip) is refused and reported.
    if (heading_found_[s]) {
      if (std::abs(yaw) > Alignment::kImplausibleTurnDeg * kRadPerDeg) {
        align_.reject_turn(s);
        continue;
      }
      // Except while a fit against its parent's joint acceleration settles: its first estimate
      // comes from a few steps (CMU 01_07: 34 deg off), so until the evidence is settled it
      // turns at settle_turn_deg_s, as long as that evidence agrees with itself.
      const double lim_rad =
          acc_reference_[s] && heading_.reference(s) == kSegmentParent[s] && heading_.settling(s)
              ? opt_.heading_from_motion.settle_turn_deg_s * kRadPerDeg * kHeadingEveryS
              : max_turn_rad;
      yaw = std::clamp(yaw, -lim_rad, lim_rad);
    }
    if (refine_[s]) {
      const double total_rad = std::clamp(turned_rad_[s] + yaw, -refine_max_rad, refine_max_rad);
      yaw = total_rad - turned_rad_[s];
      turned_rad_[s] = total_rad;
      if (std::abs(yaw) < 1e-9) continue;
    }
    heading_found_[s] = true;
    // The sensor's frame turns by yaw: once its heading was lost since the calibration, its
    // heading alone (the mounting is known), else its mounting keeps the segment's calibration
    // pose (its facing was sought).
    if (align_.segment(s).lost_headings > 0)
      align_.turn_heading(s, yaw, AlignSource::joint, align_.segment(s).heading_sigma_deg);
    else
      align_.realign(s, yaw, AlignSource::joint, align_.segment(s).heading_sigma_deg);
    heading_.applied(s, yaw);
  }
}

// A held segment's heading follows its fit's drift: beyond the fit's own bias, slowly, about the
// vertical, and half of it is its reference's (which is settled too, e.g. the pelvis): neither
// 6D frame is known better than the other, and one that drifts fast (a forearm whose gyro
// clipped) is then pulled back by each neighbour rather than pulling the segments below it off.
// CMU 6D with the mounting motion, a 5 min session scored over its last minute, 24 clips: the
// held segment alone turning 0.855 x the ideally aligned filters, worst segment excess 18.8 deg
// (01_07's hand after its forearm); half and half 0.762 x, 8.0 deg.
void BodyTracker::follow_drift(int s, double yaw_rad) {
  const HeadingFromMotionOptions& o = opt_.heading_from_motion;
  const double dead_band_rad = o.hold_dead_band_deg * kRadPerDeg;
  if (std::abs(yaw_rad) <= dead_band_rad) return;
  if (std::abs(yaw_rad) > Alignment::kImplausibleTurnDeg * kRadPerDeg) {
    align_.reject_turn(s);
    return;
  }
  const double max_rad = o.hold_turn_deg_s * kRadPerDeg * kHeadingEveryS;
  const double yaw = std::clamp(yaw_rad - std::copysign(dead_band_rad, yaw_rad), -max_rad, max_rad);
  const int ref = heading_.reference(s);
  const bool share = settled(ref);
  turn_held(s, share ? 0.5 * yaw : yaw);
  if (share) turn_held(ref, -0.5 * yaw);
}

void BodyTracker::turn_held(int s, double yaw_rad) {
  align_.turn_heading(s, yaw_rad, AlignSource::joint, align_.segment(s).heading_sigma_deg);
  if (heading_.reference(s) >= 0) heading_.applied(s, yaw_rad);
  for (int t = 0; t < kSegmentCount; ++t)
    if (heading_.reference(t) == s) heading_.reference_turned(t, yaw_rad);
}

// A sensor the calibration found far off the body heading, whose field looks like the earth's
// (norm within mag_dist.norm_th of the rig's median: a turned field no test of its own can
// catch), is watched: its heading held and re-checked (local_field_watch.hpp). A field that
// does not look like the earth's is the filter's own disturbance tests' business.
void BodyTracker::suspect_local_fields(const CalibrationResult& r) {
  std::array<double, kSegmentCount> norm{};
  std::array<double, kSegmentCount> sorted{};
  int n = 0;
  for (size_t k = 0; k < sensors_.size(); ++k) {
    const int sg = sensors_[k].segment;
    if (sg < 0 || !has_mag_[k] || n >= kSegmentCount) continue;
    norm[sg] = filters_[k].state().mag_dist.norm_dip[0];
    sorted[n++] = norm[sg];
  }
  if (n == 0) return;
  std::sort(sorted.begin(), sorted.begin() + n);
  const double median = sorted[n / 2];
  const double norm_th = opt_.filter.mag_dist.norm_th;
  for (size_t k = 0; k < sensors_.size(); ++k) {
    const int sg = sensors_[k].segment;
    if (sg < 0 || !has_mag_[k] || r.heading_off_normal_rad[sg] == 0) continue;
    if (std::abs(norm[sg] - median) > norm_th * median) continue;
    field_watch_[k].suspect(-r.heading_off_normal_rad[sg], last_output_[k], norm_th);
  }
}

void BodyTracker::start_calibration(CalibrationPose pose, int64_t t_start_ns,
                                    bool mounting_motion) {
  result_.reset();
  capturer_.start(pose, t_start_ns);
  mounting_motion_next_ = mounting_motion;
}

std::optional<CalibrationResult> BodyTracker::take_calibration_result() {
  if (!result_) return std::nullopt;  // (asked after every sample)
  std::optional<CalibrationResult> r;
  r.swap(result_);
  return r;
}

void BodyTracker::set_sensor_live(int i, bool live) {
  if (i < 0 || i >= sensor_count()) return;
  const int seg = sensors_[static_cast<size_t>(i)].segment;
  if (seg >= 0) skeleton_.set_sensor_live(seg, live);
}

}  // namespace mocap::rig
