// RigEngine: a rig config -> rig::BodyTracker, plus the calibration file and log lines.
#include "mocap/daemon/rig_engine.hpp"

#include <filesystem>
#include <stdexcept>

#include "mocap/core/segments.hpp"
#include "mocap/drivers/device.hpp"
#include "mocap/skeleton/body_model.hpp"

namespace mocap::daemon {

std::vector<rig::TrackerSensor> tracker_sensors(const Config& cfg) {
  std::vector<rig::TrackerSensor> out;
  for (const auto& s : cfg.sensors) {
    rig::TrackerSensor t;
    if (auto seg = segment_from_name(s.segment)) t.segment = index(*seg);
    if (const auto& g = s.gyr_scale) t.gyr_scale = Eigen::Vector3d((*g)[0], (*g)[1], (*g)[2]);
    if (const auto& n = s.site_normal)
      t.site_normal_body = Eigen::Vector3d((*n)[0], (*n)[1], (*n)[2]);
    t.fused_on_device = fused_on_device(s.driver);
    out.push_back(t);
  }
  return out;
}

rig::TrackerOptions tracker_options(const Config& cfg) {
  rig::TrackerOptions o;
  o.filter = cfg.filter.params;
  o.use_mag = cfg.filter.use_mag;
  o.skeleton.root.pinned = !cfg.body.root_motion;
  o.skeleton.stale_after_ns = static_cast<int64_t>(cfg.pipeline.stale_after_ms * 1e6);
  o.capture.capture_s = cfg.calibration.capture_s;
  const auto& a = cfg.calibration.heading_axis_sensor;
  o.calibration.heading_axis_sensor = Eigen::Vector3d(a[0], a[1], a[2]);
  o.calibration.heading = cfg.calibration.heading;
  return o;
}

RigEngine::RigEngine(const Config& cfg, Logger* log)
    : cfg_(cfg),
      log_(log),
      tracker_(BodyModel(cfg.body.model), cfg.body.limits, tracker_sensors(cfg),
               tracker_options(cfg)) {
  const std::string& file = cfg.calibration.file;
  if (!file.empty() && std::filesystem::exists(file)) {
    tracker_.set_calibration(load_calibration(file));
    saved_revision_ = tracker_.skeleton().calibration_revision();
    if (log_) log_->info("calibration loaded from %s", file.c_str());
  }
  if (!file.empty()) saver_ = std::make_unique<CalibrationSaver>(file, log_);
}

RigEngine::~RigEngine() = default;

void RigEngine::flush_calibration_file() {
  if (saver_) saver_->flush();
}

void RigEngine::on_sample(int i, const ImuSample& s) {
  tracker_.on_sample(i, s);
  after_sample(s);
}

FilterOutput RigEngine::prefilter(int i, const ImuSample& s) {
  if (i < 0 || i >= tracker_.sensor_count()) return {};
  return tracker_.filter_sample(i, s);
}

void RigEngine::on_prefiltered(int i, const ImuSample& s, const FilterOutput& o) {
  tracker_.track_sample(i, s, o);
  after_sample(s);
}

void RigEngine::after_sample(const ImuSample& s) {
  if (auto r = tracker_.take_calibration_result()) {
    calib_message_ = r->message;
    if (r->ok()) {
      save_calibration_file(s.t_host_ns);
      if (log_) log_->info("calibration done: %s", r->message.c_str());
    } else if (log_) {
      log_->warn(
          "calibration %s: %s",
          r->status == rig::CalibrationStatus::need_tpose ? "needs a T-pose next" : "refused",
          r->message.c_str());
    }
  }
}

void RigEngine::set_sensor_live(int i, bool live) {
  tracker_.set_sensor_live(i, live);
}

void RigEngine::build_frame(int64_t t_ns, PoseFrame& out) {
  tracker_.solve(t_ns, out);
  // A heading reset changed the calibration: save it, throttled.
  if (tracker_.skeleton().calibration_revision() != saved_revision_ &&
      (saved_t_ns_ == INT64_MIN || static_cast<double>(t_ns - saved_t_ns_) * 1e-9 >= kSaveEveryS))
    save_calibration_file(t_ns);
}

void RigEngine::save_calibration_file(int64_t t_ns) {
  saved_revision_ = tracker_.skeleton().calibration_revision();
  saved_t_ns_ = t_ns;
  const Calibration& c = tracker_.skeleton().calibration();
  if (saver_ && c.valid) saver_->offer(c);
}

CalibrationProgress RigEngine::calibration_progress() const {
  CalibrationProgress p;
  const size_t n = std::min(calib_message_.size(), p.message.size() - 1);
  std::copy_n(calib_message_.begin(), n, p.message.begin());
  p.mounting_motion = tracker_.watching_mounting_motion();
  const rig::Alignment& a = tracker_.alignment();
  for (int s = 0; s < kSegmentCount; ++s) {
    const rig::SegmentAlignment& g = a.segment(s);
    SegmentAlignmentStatus& o = p.segments[static_cast<size_t>(s)];
    // A sensor sharing the earth frame has the body heading's mounting yaw.
    const bool body = g.aligned && !g.own_frame;
    o.mounting_source = body ? a.body_heading_source() : g.facing.source;
    o.mounting_sigma_deg =
        static_cast<float>(body ? a.body_heading_sigma_deg() : g.facing.sigma_deg);
    o.heading_source = g.heading_source;
    o.heading_sigma_deg = static_cast<float>(g.heading_sigma_deg);
    o.rejected_turns = g.rejected_turns;
    o.corrected_turns = g.corrected_turns;
    o.heading_lost = g.heading_lost;
    o.lost_headings = g.lost_headings;
  }
  return p;
}

void RigEngine::calibrate(CalibrationPose pose, bool mounting_motion) {
  tracker_.start_calibration(pose, tracker_.newest_t_ns(), mounting_motion);
}

void RigEngine::reset_heading() {
  tracker_.reset_heading();
}

}  // namespace mocap::daemon
