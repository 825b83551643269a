// BodyTracker: gyro scale -> filter (or the sensor's own orientation) -> calibration capture ->
// skeleton, for one rig.
#include "mocap/rig/body_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "mocap/core/segments.hpp"
#include "mocap/core/units.hpp"
#include "mocap/skeleton/sensor_sites.hpp"

namespace mocap::rig {
namespace {

CalibratorOptions calibrator_options(const std::vector<TrackerSensor>& sensors,
                                     const TrackerOptions& o) {
  CalibratorOptions c = o.calibrator;
  if (c.heading == HeadingSource::mount_normals) {
    // A sensor lies flat on its site: its z axis is the site's outward normal.
    c.heading_axis_sensor = Eigen::Vector3d::UnitZ();
    for (const TrackerSensor& s : sensors) {
      if (s.segment < 0) continue;
      c.mount_normal_body[s.segment] =
          s.site_normal_body.squaredNorm() > 0
              ? s.site_normal_body.normalized()
              : standard_site_normal_body(static_cast<Segment>(s.segment));
    }
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
      calibrator_(rig_mapping(sensors_), calibrator_options(sensors_, opt_)),
      heading_(opt_.heading_from_motion),
      has_mag_(sensors_.size(), false),
      is_source_(sensors_.size(), false),
      q_source_(sensors_.size(), Eigen::Quaterniond::Identity()),
      prev_w_rad_s_(sensors_.size(), Eigen::Vector3d::Zero()),
      prev_w_t_ns_(sensors_.size(), 0),
      local_field_fixes_seen_(sensors_.size(), 0),
      last_output_(sensors_.size(), AttitudeFilter(opt_.filter).output()) {}

Eigen::Quaterniond BodyTracker::q_earth_sensor(int i) const {
  return q_earth_sensor(i, last_output_[static_cast<size_t>(i)]);
}

Eigen::Quaterniond BodyTracker::q_earth_sensor(int i, const FilterOutput& o) const {
  if (is_source_[static_cast<size_t>(i)]) return q_source_[static_cast<size_t>(i)];
  return opt_.use_mag ? o.q_earth_sensor : o.q_earth_sensor_6d;
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
  const Calibration& c = skeleton_.calibration();
  h.calibrated = seg >= 0 && c.valid && c.calibrated[seg];
  return h;
}

void BodyTracker::on_sample(int i, const ImuSample& in) {
  if (i < 0 || i >= sensor_count()) return;
  track_sample(i, in, filter_sample(i, in));
}

ImuSample BodyTracker::prepared(int i, const ImuSample& in) const {
  // 1. Gyro scale (1 when uncalibrated); a 6D rig ignores any magnetometer.
  ImuSample s = in;
  s.gyr_rad_s = s.gyr_rad_s.cwiseQuotient(sensors_[static_cast<size_t>(i)].gyr_scale);
  if (!opt_.use_mag) s.valid = static_cast<uint8_t>(s.valid & ~kFieldMag);
  return s;
}

FilterOutput BodyTracker::filter_sample(int i, const ImuSample& in) {
  AttitudeFilter& f = filters_[static_cast<size_t>(i)];
  // 2. Filter; an orientation source (a tracker running its own filter, sending its
  //    orientation without rates: kFieldQuat and no gyro) stands in for it (track_sample).
  if (!(in.has(kFieldQuat) && !in.has(kFieldGyr))) f.update(prepared(i, in));
  return f.output();
}

void BodyTracker::track_sample(int i, const ImuSample& in, const FilterOutput& o) {
  if (i < 0 || i >= sensor_count()) return;
  const TrackerSensor& sensor = sensors_[static_cast<size_t>(i)];
  const ImuSample s = prepared(i, in);
  if (in.has(kFieldMag)) has_mag_[static_cast<size_t>(i)] = true;
  if (s.has(kFieldQuat) && !s.has(kFieldGyr)) {
    q_source_[static_cast<size_t>(i)] = s.q_device_sensor;
    is_source_[static_cast<size_t>(i)] = true;
  }
  last_output_[static_cast<size_t>(i)] = o;
  newest_t_ns_ = std::max(newest_t_ns_, s.t_host_ns);
  const int seg = sensor.segment;
  if (seg < 0) return;
  if (o.local_field_fixes != local_field_fixes_seen_[static_cast<size_t>(i)]) {
    local_field_fixes_seen_[static_cast<size_t>(i)] = o.local_field_fixes;
    fix_mounting_after_local_field(seg, o.local_field_fix_rad);
  }
  const Eigen::Quaterniond q = q_earth_sensor(i, o);
  // 3. Calibration capture.
  if (calibrator_.capturing()) {
    calibrator_.add_sample(seg, q, s.t_host_ns, s.has(kFieldAcc) ? &s.acc_m_s2 : nullptr);
    if (calibrator_.done(s.t_host_ns)) {
      calibrator_.set_own_heading_frames(own_heading_frames());
      result_ = calibrator_.finish();
      if (result_->ok()) {
        suspect_local_fields(*result_);
        skeleton_.set_calibration(result_->calibration);
        start_heading_from_motion(*result_);
      }
    }
  }
  // 4. 6D: the heading of the sensors whose site normal could not give it, from motion.
  if (heading_.active() && s.has(kFieldGyr) && s.has(kFieldAcc)) {
    feed_heading_from_motion(i, s, q, o.gyro_bias_rad_s);
    apply_heading_from_motion(s.t_host_ns);
  }
  // 5. The segment's input: orientation and the filter's flags.
  skeleton_.set_sensor_orientation(seg, q, s.t_host_ns, sensor_health(i, o).segment_flags());
}

void BodyTracker::feed_heading_from_motion(int i, const ImuSample& s, const Eigen::Quaterniond& q,
                                           const Eigen::Vector3d& gyro_bias_rad_s) {
  constexpr double kHighPassTauS = 1.0;  // slower than a step, faster than a tilt error's drift
  constexpr double kLowPassTauS = 0.03;  // about 5 Hz
  constexpr double kGravity_m_s2 = 9.81;
  const size_t k = static_cast<size_t>(i);
  const int seg = sensors_[k].segment;
  const Calibration& c = skeleton_.calibration();
  const Eigen::Vector3d w = s.gyr_rad_s - gyro_bias_rad_s;
  const double dt_s = static_cast<double>(s.t_host_ns - prev_w_t_ns_[k]) * 1e-9;
  const bool have_dw = prev_w_t_ns_[k] != 0 && dt_s > 0 && dt_s < 0.05;
  const Eigen::Vector3d dw =
      have_dw ? Eigen::Vector3d((w - prev_w_rad_s_[k]) / dt_s) : Eigen::Vector3d::Zero();
  prev_w_rad_s_[k] = w;
  prev_w_t_ns_[k] = s.t_host_ns;
  if (!have_dw) return;
  const Eigen::Quaterniond q_aligned = c.q_correction[seg] * q;
  // Acceleration (gravity removed, aligned earth frame) of the point r_seg of the segment's
  // frame from its sensor: the sensor's specific force plus the rotation terms.
  const auto acc_at = [&](const Eigen::Vector3d& r_seg) -> Eigen::Vector3d {
    const Eigen::Vector3d r = c.q_sensor_segment[seg] * r_seg;
    const Eigen::Vector3d a = s.acc_m_s2 + dw.cross(r) + w.cross(w.cross(r));
    return q_aligned * a - Eigen::Vector3d(0, 0, kGravity_m_s2);
  };
  // The same high-pass for both signals of a pair (it commutes with the yaw sought).
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
  // the rotation terms of the lever arm's part along the site normal (its direction in the
  // sensor frame does not depend on the alignment sought; the rest is left out); the rate
  // when acc_reference_ is false.
  if (heading_.reference(seg) >= 0) {
    if (acc_reference_[seg])
      heading_.add(seg, band_pass(acc_at(own_joint_m_[seg]), own_band_[seg]), s.t_host_ns);
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

void BodyTracker::start_heading_from_motion(const CalibrationResult& r) {
  std::array<int, kSegmentCount> reference;
  reference.fill(-1);
  const RigMapping& rig = skeleton_.rig();
  const std::array<bool, kSegmentCount> own = own_heading_frames();
  // A segment's heading is known when its sensor shares the earth frame (magnetometer) or was
  // aligned from its own site normal; the others are fitted to the nearest known one above.
  const auto known = [&](int s) {
    return rig.tracked(s) && (!own[s] || r.heading_from_own_normal[s]);
  };
  const auto known_above = [&](int s) {
    int p = kSegmentParent[s];
    while (p >= 0 && !known(p))
      p = kSegmentParent[p];
    return p;
  };
  if (opt_.calibrator.heading == HeadingSource::mount_normals)
    for (int s = 0; s < kSegmentCount; ++s)
      if (rig.tracked(s) && !known(s)) reference[s] = known_above(s);
  // Segments aligned from their own horizontal site normal are refined against the same
  // evidence, within a band (a strap tilted off the normal turns that alignment). Not the upper
  // arms: the shoulder girdle moves on the torso, which the model holds rigid, so the shoulder's
  // acceleration from the torso's sensor is off.
  refine_.fill(false);
  turned_rad_.fill(0);
  if (opt_.heading_from_motion.refine_max_deg > 0 &&
      opt_.calibrator.heading == HeadingSource::mount_normals)
    for (int s = 0; s < kSegmentCount; ++s) {
      if (!known(s) || !own[s] || !r.heading_from_own_normal[s]) continue;
      if (s == index(Segment::upper_arm_l) || s == index(Segment::upper_arm_r)) continue;
      reference[s] = known_above(s);
      refine_[s] = reference[s] >= 0;
    }
  heading_.reset(reference);
  // Joint accelerations pair a segment with its parent or, through the neck (never tracked,
  // short and stiff: held in its calibration pose), the head with the torso; further up (a
  // foot under an untracked shank) the knee's own motion would dominate: rates instead.
  const BodyModel& model = skeleton_.model();
  for (int s = 0; s < kSegmentCount; ++s) {
    acc_reference_[s] = false;
    const int p = kSegmentParent[s];
    if (reference[s] < 0 || p < 0) continue;
    const int ref = reference[s];
    if (ref != p && !(p == index(Segment::neck) && ref == kSegmentParent[p])) continue;
    acc_reference_[s] = true;
    // The joint (s's origin) in the reference's frame.
    Eigen::Vector3d joint_m = model.joint_offset_m(s);
    if (ref != p)
      joint_m =
          model.joint_offset_m(p) + q_body_segment_in_pose(r.calibration.pose, ref).conjugate() *
                                        (q_body_segment_in_pose(r.calibration.pose, p) * joint_m);
    // The own lever arm: whole where the mounting is known from the N-pose (a refined
    // segment), else only its part along the site normal.
    const Eigen::Vector3d site_m =
        standard_site_position_m(static_cast<Segment>(s), model.dimensions());
    const Eigen::Vector3d n = standard_site_normal_body(static_cast<Segment>(s));
    own_joint_m_[s] = refine_[s] ? Eigen::Vector3d(-site_m) : Eigen::Vector3d(-n.dot(site_m) * n);
    joint_in_reference_m_[s] =
        joint_m - standard_site_position_m(static_cast<Segment>(ref), model.dimensions());
  }
  own_band_.fill({});
  ref_band_.fill({});
  heading_found_ = refine_;  // a refined segment starts aligned
}

void BodyTracker::apply_heading_from_motion(int64_t t_ns) {
  constexpr int64_t kEveryNs = 100'000'000;  // 10 Hz: the alignment is a slow constant
  constexpr double kMinTurnRad = 0.1 * kRadPerDeg;
  if (t_ns - heading_applied_t_ns_ < kEveryNs) return;
  const double max_turn_rad =
      opt_.heading_from_motion.max_drift_deg_s * kRadPerDeg * static_cast<double>(kEveryNs) * 1e-9;
  heading_applied_t_ns_ = t_ns;
  const double dead_band_rad = opt_.heading_from_motion.refine_dead_band_deg * kRadPerDeg;
  const double refine_max_rad = opt_.heading_from_motion.refine_max_deg * kRadPerDeg;
  Calibration c = skeleton_.calibration();
  bool changed = false;
  for (int s = 0; s < kSegmentCount; ++s) {
    double yaw = 0;
    if (!heading_.estimate(s, yaw)) continue;
    if (std::abs(yaw) < kMinTurnRad) continue;
    // A refined segment moves only when the evidence is off by more than the fit's own bias
    // (model mismatch: joint centres, carrying angle), and stays within its band.
    if (refine_[s]) {
      if (std::abs(yaw) <= dead_band_rad) continue;
      yaw -= std::copysign(dead_band_rad, yaw);
    }
    // The first estimate aligns; afterwards the alignment only follows the slow drift of the
    // 6D heading, so a stretch of misleading motion cannot turn it over.
    if (heading_found_[s]) yaw = std::clamp(yaw, -max_turn_rad, max_turn_rad);
    if (refine_[s]) {
      const double total_rad = std::clamp(turned_rad_[s] + yaw, -refine_max_rad, refine_max_rad);
      yaw = total_rad - turned_rad_[s];
      turned_rad_[s] = total_rad;
      if (std::abs(yaw) < 1e-9) continue;
    }
    heading_found_[s] = true;
    // The sensor's frame turns by yaw; its mounting keeps the segment's calibration pose:
    // q_ss' = q_ss T^-1 Y^-1 T with T the segment's orientation at calibration.
    const Eigen::Quaterniond y(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
    const Eigen::Quaterniond t = Eigen::Quaterniond(Eigen::AngleAxisd(c.heading_deg * kRadPerDeg,
                                                                      Eigen::Vector3d::UnitZ())) *
                                 q_body_segment_in_pose(c.pose, s);
    c.q_correction[s] = (y * c.q_correction[s]).normalized();
    c.q_sensor_segment[s] =
        (c.q_sensor_segment[s] * t.conjugate() * y.conjugate() * t).normalized();
    heading_.applied(s, yaw);
    changed = true;
  }
  if (changed) skeleton_.set_calibration(c);
}

// A sensor the calibration found far off its site normal, whose field looks like the earth's
// (norm within mag_dist.norm_th of the rig's median: a turned field no test of its own can
// catch), is handed to its filter to hold and re-check. A field that does not look like the
// earth's is the filter's own disturbance tests' business.
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
  for (size_t k = 0; k < sensors_.size(); ++k) {
    const int sg = sensors_[k].segment;
    if (sg < 0 || !has_mag_[k] || r.heading_off_normal_rad[sg] == 0) continue;
    if (std::abs(norm[sg] - median) > opt_.filter.mag_dist.norm_th * median) continue;
    filters_[k].suspect_local_field(-r.heading_off_normal_rad[sg]);
  }
}

// The calibration took this sensor's orientation with the local field's heading; its filter
// has now turned by turn_rad onto the earth's: the mounting turns alike, as if the
// calibration had seen the true heading (q_ss' = q_ss B^-1 Rz(-turn) B, B the segment's
// orientation in the calibration pose).
void BodyTracker::fix_mounting_after_local_field(int seg, double turn_rad) {
  Calibration c = skeleton_.calibration();
  if (seg < 0 || !c.valid || !c.calibrated[seg]) return;
  const Eigen::Quaterniond b =
      Eigen::Quaterniond(Eigen::AngleAxisd(c.heading_deg * kRadPerDeg, Eigen::Vector3d::UnitZ())) *
      q_body_segment_in_pose(c.pose, seg);
  const Eigen::Quaterniond y(Eigen::AngleAxisd(-turn_rad, Eigen::Vector3d::UnitZ()));
  c.q_sensor_segment[seg] = (c.q_sensor_segment[seg] * b.conjugate() * y * b).normalized();
  skeleton_.set_calibration(c);
}

void BodyTracker::start_calibration(CalibrationPose pose, int64_t t_start_ns) {
  result_.reset();
  calibrator_.start(pose, t_start_ns);
}

std::optional<CalibrationResult> BodyTracker::take_calibration_result() {
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
