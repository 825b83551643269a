// PipelineCore: drives the engine sample by sample, tracks per-sensor health, runs the
// calibration countdown and publishes frames. Deterministic given its inputs.
#include "mocap/daemon/pipeline_core.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "mocap/core/units.hpp"

namespace mocap::daemon {

namespace {

bool finite_sample(const ImuSample& s) {
  return s.gyr_rad_s.allFinite() && s.acc_m_s2.allFinite() && s.mag_uT.allFinite() &&
         s.q_device_sensor.coeffs().allFinite();
}

}  // namespace

PipelineCore::PipelineCore(const PipelineConfig& cfg, const CalibrationConfig& calib,
                           std::vector<SensorInfo> sensors, PoseEngine& engine)
    : cfg_(cfg),
      calib_(calib),
      sensors_(std::move(sensors)),
      engine_(engine),
      health_(sensors_.size()),
      period_ns_(static_cast<int64_t>(std::llround(1e9 / cfg.rate_hz))) {
  if (sensors_.size() > static_cast<size_t>(kMaxSensors)) sensors_.resize(kMaxSensors);
  reset_pose(frame_);
  sinks_.reserve(8);
}

void PipelineCore::remove_sink(outputs::Output* sink) {
  sinks_.erase(std::remove(sinks_.begin(), sinks_.end(), sink), sinks_.end());
}

bool PipelineCore::accepts(const ImuSample& s) const {
  return s.sensor_id < sensors_.size() && finite_sample(s);
}

void PipelineCore::process(const ImuSample& s) {
  if (!take(s)) return;
  engine_.on_sample(s.sensor_id, s);
  taken(s);
}

void PipelineCore::process(const ImuSample& s, const FilterOutput& o) {
  if (!take(s)) return;
  engine_.on_prefiltered(s.sensor_id, s, o);
  taken(s);
}

bool PipelineCore::take(const ImuSample& s) {
  if (!accepts(s)) {
    ++rejected_;  // NaN never reaches a pose; unknown sensors are ignored
    return false;
  }
  const int i = s.sensor_id;
  Health& h = health_[i];
  if (h.window_start_ns == INT64_MIN || s.t_host_ns < h.window_start_ns) {
    h.window_start_ns = s.t_host_ns;
    h.window_count = 0;
  }
  ++h.window_count;
  const int64_t span = s.t_host_ns - h.window_start_ns;
  if (span >= 1'000'000'000) {
    h.rate_hz = static_cast<float>((h.window_count - 1) * 1e9 / static_cast<double>(span));
    h.window_start_ns = s.t_host_ns;
    h.window_count = 1;
  }
  if (s.flags & kFlagGapBefore) ++h.gaps;
  h.last_t_ns = std::max(h.last_t_ns, s.t_host_ns);
  h.seq = s.seq;
  h.t_device_ns = s.t_device_ns;
  sample_since_frame_ = true;
  newest_t_ns_ = have_sample_ ? std::max(newest_t_ns_, s.t_host_ns) : s.t_host_ns;
  have_sample_ = true;
  if (!h.live) {
    h.live = true;
    engine_.set_sensor_live(i, true);
  }
  return true;
}

void PipelineCore::taken(const ImuSample& s) {
  ++samples_;
  if (cfg_.publish_every_sample) publish_frame(s.t_host_ns);
}

void PipelineCore::advance_clock_to(int64_t t_ns) {
  if (next_frame_ns_ == INT64_MIN) {
    next_frame_ns_ = t_ns + period_ns_;
    return;
  }
  while (t_ns >= next_frame_ns_) {
    publish_frame(next_frame_ns_);
    next_frame_ns_ += period_ns_;
  }
}

void PipelineCore::request_calibration(CalibrationPose pose, int64_t t_now_ns,
                                       bool mounting_motion) {
  calibrating_ = true;
  state_changed_ = true;
  calib_pose_ = pose;
  calib_mounting_motion_ = mounting_motion && pose == CalibrationPose::npose;
  calib_at_ns_ = t_now_ns + static_cast<int64_t>(calib_.countdown_s * 1e9);
  maybe_finish_calibration(t_now_ns);
}

void PipelineCore::maybe_finish_calibration(int64_t t_now_ns) {
  if (calibrating_ && t_now_ns >= calib_at_ns_) {
    engine_.calibrate(calib_pose_, calib_mounting_motion_);
    calibrating_ = false;
    state_changed_ = true;
  }
}

void PipelineCore::set_frame_flag(uint32_t flag, bool on) {
  const uint32_t flags = on ? (extra_flags_ | flag) : (extra_flags_ & ~flag);
  state_changed_ = state_changed_ || flags != extra_flags_;
  extra_flags_ = flags;
}

void PipelineCore::set_external_counters(int sensor, uint32_t drops, uint32_t errors) {
  if (sensor < 0 || sensor >= static_cast<int>(health_.size())) return;
  health_[sensor].drops = drops;
  health_[sensor].errors = errors;
}

void PipelineCore::set_connected(int sensor, bool connected) {
  if (sensor < 0 || sensor >= static_cast<int>(health_.size())) return;
  health_[sensor].link = connected ? 1 : 0;
}

void PipelineCore::publish_frame(int64_t t_now_ns) {
  maybe_finish_calibration(t_now_ns);
  const int64_t stale_ns = static_cast<int64_t>(cfg_.stale_after_ms * 1e6);
  // Every frame has a time of its own: the newest sample's (a frame carries the pose of that
  // time; docs/accuracy.md shows holding it beats predicting). A sample older than the last
  // frame (sensors' clocks map their samples to slightly different delays; the merge is by
  // time only within one drain) still changes the pose: its frame is 1 ns after the last, so
  // it is never held back until a newer sample comes (per-sample mode would otherwise skip its
  // frame). No sample since the last frame: no new pose, no frame, unless a frame flag or the
  // calibration state changed or the sensors fell silent for stale_after_ms: then a frame at
  // the clock's time says so. Before any sample (a flag set at start-up) that is the clock's
  // time too: a frame at 0 put a recording's first pose hours before its second (an imported
  // take's keys beyond Blender's last frame once the host was up 12 h).
  int64_t t_frame_ns = have_sample_ ? newest_t_ns_ : t_now_ns;
  if (published_t_ns_ != INT64_MIN && t_frame_ns <= published_t_ns_) {
    if (sample_since_frame_) {
      t_frame_ns = published_t_ns_ + 1;
    } else {
      if (t_now_ns <= published_t_ns_ || (!state_changed_ && t_now_ns - published_t_ns_ < stale_ns))
        return;
      t_frame_ns = t_now_ns;
    }
  }
  published_t_ns_ = t_frame_ns;
  state_changed_ = false;
  sample_since_frame_ = false;
  // Sensors that went silent degrade their segment (the engine infers it from the parent).
  for (size_t i = 0; i < sensors_.size(); ++i) {
    Health& h = health_[i];
    const bool fresh = h.last_t_ns != INT64_MIN && t_now_ns - h.last_t_ns <= stale_ns;
    if (h.live && !fresh) {
      h.live = false;
      engine_.set_sensor_live(static_cast<int>(i), false);
    }
  }
  engine_.build_frame(t_frame_ns, frame_);
  frame_.frame = ++frame_no_;
  frame_.t_ns = t_frame_ns;
  // 0 (unknown) too when a recording's offset is absurd enough to overflow.
  int64_t t_unix_ns = 0;
  frame_.t_unix_ns =
      unix_offset_known_ && !__builtin_add_overflow(t_frame_ns, unix_offset_ns_, &t_unix_ns)
          ? t_unix_ns
          : 0;
  frame_.flags = (frame_.flags & kFrameCalibrated) | extra_flags_;
  if (calibrating_) {
    frame_.flags |= kFrameCalibrating;
    frame_.calib_countdown_s =
        static_cast<float>(std::max<int64_t>(0, calib_at_ns_ - t_now_ns) * 1e-9);
  } else {
    frame_.calib_countdown_s = 0;
  }
  frame_.sensor_count = static_cast<uint32_t>(sensors_.size());
  for (size_t i = 0; i < sensors_.size(); ++i) {
    const Health& h = health_[i];
    SensorStatus& st = frame_.sensors[i];
    std::memset(st.name, 0, sizeof st.name);
    std::strncpy(st.name, sensors_[i].name.c_str(), sizeof st.name - 1);
    st.segment = static_cast<int8_t>(sensors_[i].segment);
    const bool has_data = h.last_t_ns != INT64_MIN;
    st.last_age_ms =
        has_data ? static_cast<float>(std::max<int64_t>(0, t_now_ns - h.last_t_ns) * 1e-6) : 0.f;
    if (!has_data)
      st.state = h.link == 1 ? kConnecting : kAbsent;
    else
      st.state = h.live ? kStreaming : h.link == 0 ? kDisconnected : kStale;
    st.rate_hz = h.live ? h.rate_hz : 0.f;
    st.drops = h.drops + h.gaps;
    st.errors = h.errors;
    const SensorHealth fs = engine_.sensor_health(static_cast<int>(i));
    st.flags = static_cast<uint16_t>(fs.segment_flags() | (h.live ? 0u : uint32_t{kSegStale}));
    st.gyro_bias_dps = static_cast<float>(fs.gyro_bias_rad_s * kDegPerRad);
    st.heading_sigma_deg = static_cast<float>(fs.heading_sigma_rad * kDegPerRad);
    st.seq = h.seq;
    st.t_device_ns = h.t_device_ns;
    if (sensors_[i].segment >= 0 && !h.live) frame_.segment_flags[sensors_[i].segment] |= kSegStale;
  }
  for (outputs::Output* s : sinks_)
    s->on_frame(frame_);
}

}  // namespace mocap::daemon
