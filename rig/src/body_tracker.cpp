// BodyTracker: gyro scale -> filter (or the sensor's own orientation) -> calibration capture ->
// skeleton, for one rig.
#include "mocap/rig/body_tracker.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "mocap/core/segments.hpp"
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
      q_source_(sensors_.size(), Eigen::Quaterniond::Identity()) {}

Eigen::Quaterniond BodyTracker::q_earth_sensor(int i) const {
  if (is_source_[static_cast<size_t>(i)]) return q_source_[static_cast<size_t>(i)];
  const AttitudeFilter& f = filters_[static_cast<size_t>(i)];
  return opt_.use_mag ? f.q_earth_sensor() : f.q_earth_sensor_6d();
}

void BodyTracker::on_sample(int i, const ImuSample& in) {
  if (i < 0 || i >= sensor_count()) return;
  const TrackerSensor& sensor = sensors_[static_cast<size_t>(i)];
  AttitudeFilter& f = filters_[static_cast<size_t>(i)];
  // 1. Gyro scale (1 when uncalibrated); a 6D rig ignores any magnetometer.
  ImuSample s = in;
  if (s.has(kFieldMag)) has_mag_[static_cast<size_t>(i)] = true;
  s.gyr_rad_s = s.gyr_rad_s.cwiseQuotient(sensor.gyr_scale);
  if (!opt_.use_mag) s.valid = static_cast<uint8_t>(s.valid & ~kFieldMag);
  // 2. Filter; an orientation source (a tracker running its own filter, sending its
  //    orientation without rates: kFieldQuat and no gyro) stands in for it.
  if (s.has(kFieldQuat) && !s.has(kFieldGyr)) {
    q_source_[static_cast<size_t>(i)] = s.q_device_sensor;
    is_source_[static_cast<size_t>(i)] = true;
  } else {
    f.update(s);
  }
  newest_t_ns_ = std::max(newest_t_ns_, s.t_host_ns);
  const int seg = sensor.segment;
  if (seg < 0) return;
  const Eigen::Quaterniond q = q_earth_sensor(i);
  // 3. Calibration capture.
  if (calibrator_.capturing()) {
    calibrator_.add_sample(seg, q, s.t_host_ns, s.has(kFieldAcc) ? &s.acc_m_s2 : nullptr);
    if (calibrator_.done(s.t_host_ns)) {
      calibrator_.set_own_heading_frames(own_heading_frames());
      result_ = calibrator_.finish();
      if (result_->ok()) {
        skeleton_.set_calibration(result_->calibration);
        start_heading_from_motion(*result_);
      }
    }
  }
  // 4. 6D: the heading of the sensors whose site normal could not give it, from motion.
  if (heading_.active() && s.has(kFieldGyr)) {
    const Eigen::Vector3d w_sensor = s.gyr_rad_s - f.gyro_bias_rad_s();
    heading_.add(seg, skeleton_.calibration().q_correction[seg] * (q * w_sensor), s.t_host_ns);
    apply_heading_from_motion(s.t_host_ns);
  }
  // 5. The segment's input: orientation and the filter's flags.
  const uint32_t flags = (f.at_rest() ? uint32_t{kSegAtRest} : 0u) |
                         (opt_.use_mag && f.mag_disturbed() ? uint32_t{kSegMagDisturbed} : 0u) |
                         (opt_.use_mag && f.mag_no_reference() ? uint32_t{kSegMagNoReference} : 0u);
  skeleton_.set_sensor_orientation(seg, q, s.t_host_ns, flags);
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
  if (opt_.calibrator.heading == HeadingSource::mount_normals)
    for (int s = 0; s < kSegmentCount; ++s) {
      if (!rig.tracked(s) || known(s)) continue;
      int p = kSegmentParent[s];
      while (p >= 0 && !known(p))
        p = kSegmentParent[p];
      reference[s] = p;
    }
  heading_.reset(reference);
}

void BodyTracker::apply_heading_from_motion(int64_t t_ns) {
  constexpr int64_t kEveryNs = 100'000'000;  // 10 Hz: the alignment is a slow constant
  constexpr double kMinTurnRad = 0.1 * std::numbers::pi / 180;
  if (t_ns - heading_applied_t_ns_ < kEveryNs) return;
  heading_applied_t_ns_ = t_ns;
  Calibration c = skeleton_.calibration();
  bool changed = false;
  for (int s = 0; s < kSegmentCount; ++s) {
    double yaw = 0;
    if (!heading_.estimate(s, yaw) || std::abs(yaw) < kMinTurnRad) continue;
    // The sensor's frame turns by yaw; its mounting keeps the segment's calibration pose:
    // q_ss' = q_ss T^-1 Y^-1 T with T the segment's orientation at calibration.
    const Eigen::Quaterniond y(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
    const Eigen::Quaterniond t =
        Eigen::Quaterniond(
            Eigen::AngleAxisd(c.heading_deg * std::numbers::pi / 180, Eigen::Vector3d::UnitZ())) *
        q_body_segment_in_pose(c.pose, s);
    c.q_correction[s] = (y * c.q_correction[s]).normalized();
    c.q_sensor_segment[s] =
        (c.q_sensor_segment[s] * t.conjugate() * y.conjugate() * t).normalized();
    heading_.applied(s, yaw);
    changed = true;
  }
  if (changed) skeleton_.set_calibration(c);
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
