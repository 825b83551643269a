// RigEngine: filter -> calibration -> skeleton for the sensors of a rig config.
#include "mocap/daemon/rig_engine.hpp"

#include <filesystem>
#include <stdexcept>

#include "mocap/core/segments.hpp"
#include "mocap/core/units.hpp"
#include "mocap/filter/filter_param_names.hpp"
#include "mocap/skeleton/body_model.hpp"
#include "mocap/skeleton/joint_limits.hpp"
#include "mocap/skeleton/sensor_sites.hpp"

namespace mocap::daemon {

namespace {

RigMapping rig_mapping(const Config& cfg) {
  RigMapping r = RigMapping::none();
  for (size_t i = 0; i < cfg.sensors.size(); ++i)
    if (auto seg = segment_from_name(cfg.sensors[i].segment))
      r.sensor_for_segment[index(*seg)] = static_cast<int>(i);
  return r;
}

SkeletonOptions skeleton_options(const Config& cfg) {
  SkeletonOptions o;
  o.limit_policy = cfg.body.enforce_limits ? LimitPolicy::clamp : LimitPolicy::report;
  o.root.pinned = !cfg.body.root_motion;
  o.stale_after_ns = static_cast<int64_t>(cfg.pipeline.stale_after_ms * 1e6);
  o.hinge_refine.enabled = cfg.calibration.refine_hinges;
  o.heading_coupling.enabled = cfg.calibration.heading_coupling;
  o.relative_mag_heading.enabled = cfg.calibration.relative_mag_heading && cfg.filter.use_mag;
  for (const auto& s : cfg.sensors)
    if (auto seg = segment_from_name(s.segment); seg && s.gyr_scale)
      o.relative_mag_heading.gyro_scale_calibrated[index(*seg)] = true;
  return o;
}

CalibratorOptions calibrator_options(const Config& cfg) {
  CalibratorOptions o;
  o.capture_s = cfg.calibration.capture_s;
  const auto& a = cfg.calibration.heading_axis_sensor;
  o.heading_axis_sensor = Eigen::Vector3d(a[0], a[1], a[2]);
  if (cfg.calibration.heading == "mean_sensors") {
    o.heading = HeadingSource::mean_sensors;
  } else if (cfg.calibration.heading == "mount_normals") {
    // A sensor lies flat on its site: its z axis is the site's outward normal.
    o.heading = HeadingSource::mount_normals;
    o.heading_axis_sensor = Eigen::Vector3d::UnitZ();
    for (const auto& s : cfg.sensors) {
      const auto seg = segment_from_name(s.segment);
      if (!seg) continue;
      o.mount_normal_body[index(*seg)] =
          s.site_normal
              ? Eigen::Vector3d((*s.site_normal)[0], (*s.site_normal)[1], (*s.site_normal)[2])
                    .normalized()
              : standard_site_normal_body(*seg);
    }
  } else {
    o.heading = HeadingSource::pelvis_sensor;
  }
  return o;
}

}  // namespace

FilterParams filter_params(const FilterConfig& f) {
  FilterParams p;
  for (const auto& [k, v] : f.params) {
    std::string err;
    if (!set_filter_param(p, k + "=" + v, err))
      throw std::invalid_argument("filter." + k + ": " + err);
  }
  return p;
}

RigEngine::RigEngine(const Config& cfg, Logger* log)
    : cfg_(cfg),
      log_(log),
      consensus_(cfg.sensors.size()),
      skeleton_(BodyModel(cfg.body.model), cfg.body.limits, rig_mapping(cfg),
                skeleton_options(cfg)),
      calibrator_(rig_mapping(cfg), calibrator_options(cfg)) {
  const FilterParams fp = filter_params(cfg.filter);
  filters_.assign(cfg.sensors.size(), AttitudeFilter(fp));
  for (const auto& s : cfg.sensors) {
    auto seg = segment_from_name(s.segment);
    segment_of_.push_back(seg ? index(*seg) : -1);
    const auto& g = s.gyr_scale;
    gyr_scale_.push_back(g ? Eigen::Vector3d((*g)[0], (*g)[1], (*g)[2]) : Eigen::Vector3d::Ones());
  }
  const std::string& file = cfg.calibration.file;
  if (!file.empty() && std::filesystem::exists(file)) {
    skeleton_.set_calibration(load_calibration(file));
    saved_revision_ = skeleton_.calibration_revision();
    if (log_) log_->info("calibration loaded from %s", file.c_str());
  }
  if (!file.empty()) saver_ = std::make_unique<CalibrationSaver>(file, log_);
}

RigEngine::~RigEngine() = default;

void RigEngine::flush_calibration_file() {
  if (saver_) saver_->flush();
}

void RigEngine::on_sample(int i, const ImuSample& in) {
  AttitudeFilter& f = filters_[i];
  // The sensor's gyro scale from its table-spin calibration (1 when uncalibrated).
  ImuSample s = in;
  s.gyr_rad_s = s.gyr_rad_s.cwiseQuotient(gyr_scale_[i]);
  f.update(s);
  newest_t_ns_ = std::max(newest_t_ns_, s.t_host_ns);
  // Every sensor of the body sees the same earth field: a reference that differs from the
  // others' median (a magnet beside it at start-up) is replaced (low rate, docs/filter.md).
  if (cfg_.filter.use_mag) {
    const int replaced = consensus_.step(newest_t_ns_, filters_);
    if (replaced > 0 && log_)
      log_->warn(
          "%d sensor(s) took a reference field unlike the rig's (%.1f uT, dip %.1f deg): "
          "replaced by the rig's (a magnet or steel nearby at start-up?)",
          replaced, consensus_.norm_uT(), consensus_.dip_rad() / kRadPerDeg);
  }
  const int seg = segment_of_[i];
  if (seg < 0) return;
  const Eigen::Quaterniond q = cfg_.filter.use_mag ? f.q_earth_sensor() : f.q_earth_sensor_6d();
  const uint32_t flags = (f.at_rest() ? uint32_t{kSegAtRest} : 0u) |
                         (f.mag_disturbed() ? uint32_t{kSegMagDisturbed} : 0u) |
                         (f.mag_no_reference() ? uint32_t{kSegMagNoReference} : 0u);
  skeleton_.set_sensor_orientation(seg, q, s.t_host_ns, flags, f.mag_heading_rad());
  if (calibrator_.capturing()) {
    calibrator_.add_sample(seg, q, s.t_host_ns, s.has(kFieldAcc) ? &s.acc_m_s2 : nullptr);
    if (calibrator_.done(s.t_host_ns)) {
      CalibrationResult r = calibrator_.finish();
      calib_message_ = r.message;
      if (r.ok()) {
        skeleton_.set_calibration(r.calibration);
        // The calibration absorbed each filter's heading error of this moment (hard-iron
        // residual): keep it when the offset is learnt later (docs/filter.md).
        for (AttitudeFilter& af : filters_)
          af.anchor_heading();
        save_calibration_file(s.t_host_ns);
        if (log_) log_->info("calibration done: %s", r.message.c_str());
      } else if (log_) {
        log_->warn("calibration %s: %s",
                   r.status == CalibrationStatus::need_tpose ? "needs a T-pose next" : "refused",
                   r.message.c_str());
      }
    }
  }
}

void RigEngine::build_frame(int64_t t_ns, PoseFrame& out) {
  skeleton_.solve(out);
  // The refinement (or a heading reset) changed the calibration: save it, throttled.
  if (skeleton_.calibration_revision() != saved_revision_ &&
      (saved_t_ns_ == INT64_MIN ||
       static_cast<double>(t_ns - saved_t_ns_) * 1e-9 >= kSaveRefinedEveryS))
    save_calibration_file(t_ns);
}

void RigEngine::save_calibration_file(int64_t t_ns) {
  saved_revision_ = skeleton_.calibration_revision();
  saved_t_ns_ = t_ns;
  const Calibration& c = skeleton_.calibration();
  if (saver_ && c.valid) saver_->offer(c);
}

CalibrationProgress RigEngine::calibration_progress() const {
  CalibrationProgress p;
  const size_t n = std::min(calib_message_.size(), p.message.size() - 1);
  std::copy_n(calib_message_.begin(), n, p.message.begin());
  const HingeAxisRefiner& r = skeleton_.hinge_refiner();
  p.refining = cfg_.calibration.refine_hinges && skeleton_.calibration().valid;
  p.needed_travel_deg = static_cast<float>(r.options().min_travel_deg);
  static_assert(std::tuple_size_v<decltype(p.mountings)> == kRefinePairs.size());
  for (size_t h = 0; h < kRefinePairs.size(); ++h) {
    const HingeEstimate& e = r.hinges()[h];
    CalibrationProgress::Mounting& m = p.mountings[h];
    const RefinePair& pr = kRefinePairs[h];
    m.segment = static_cast<int8_t>(index(pr.child));
    m.tracked = skeleton_.rig().tracked(index(pr.parent)) &&
                skeleton_.rig().tracked(index(pr.child)) &&
                (pr.via < 0 || skeleton_.rig().tracked(pr.via));
    m.identified = e.valid;
    m.travel_deg = static_cast<float>(e.travel_deg);
    m.yaw_deg = static_cast<float>(e.applied_child_yaw_deg);
  }
  return p;
}

SensorFilterState RigEngine::sensor_state(int i) const {
  SensorFilterState st;
  const AttitudeFilter& f = filters_[i];
  st.initialised = f.counters().gyr_ok > 0;
  st.at_rest = f.at_rest();
  st.mag_disturbed = f.mag_disturbed();
  st.mag_no_reference = cfg_.filter.use_mag && f.mag_no_reference();
  st.gyro_bias_rad_s = f.gyro_bias_rad_s().norm();
  st.heading_sigma_rad = cfg_.filter.use_mag ? f.heading_sigma_rad() : 0.0;
  const int seg = segment_of_[i];
  st.calibrated =
      seg >= 0 && skeleton_.calibration().valid && skeleton_.calibration().calibrated[seg];
  return st;
}

void RigEngine::calibrate(CalibrationPose pose) {
  calibrator_.start(pose, newest_t_ns_);
}

void RigEngine::reset_heading() {
  skeleton_.reset_heading();
}

}  // namespace mocap::daemon
