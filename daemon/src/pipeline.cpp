// The live pipeline thread: wait for samples or the next frame tick, drain every ring, merge by
// timestamp into PipelineCore, publish frames on the wall-clock frame grid.
#include "mocap/daemon/pipeline.hpp"

#include <poll.h>
#include <signal.h>

#include <algorithm>
#include <cmath>

#include "mocap/core/thread_priority.hpp"
#include "mocap/core/time.hpp"

namespace mocap::daemon {

namespace {

/// Waits until fd is readable or the deadline passes, with nanosecond precision.
void wait_until(int fd, int64_t deadline_ns) {
  const int64_t left = deadline_ns - monotonic_ns();
  if (left <= 0) return;
  pollfd p{fd, POLLIN, 0};
  timespec ts{static_cast<time_t>(left / 1'000'000'000), static_cast<long>(left % 1'000'000'000)};
  ::ppoll(&p, 1, &ts, nullptr);
}

}  // namespace

Pipeline::Pipeline(const PipelineConfig& cfg, const CalibrationConfig& calib,
                   std::vector<SensorInfo> sensors, PoseEngine& engine, Logger log)
    : cfg_(cfg),
      reset_pose_(calib.pose),
      log_(std::move(log)),
      core_(cfg, calib, std::move(sensors), engine) {
  const size_t n = core_.sensors().size();
  for (size_t i = 0; i < n; ++i) {
    slots_.push_back(std::make_unique<Slot>());
    scratch_.emplace_back(kRingCapacity);
    device_sensor_.push_back(static_cast<int>(i));
  }
  scratch_n_.assign(n, 0);
  scratch_pos_.assign(n, 0);
  commands_.reserve(64);
  commands_work_.reserve(64);
  core_.add_sink(&tap_sink_);
  reset_pose(status_.frame);
}

Pipeline::~Pipeline() {
  stop();
}

void Pipeline::start() {
  if (running_.exchange(true)) return;
  thread_ = std::thread([this] { run(); });
}

void Pipeline::stop() {
  if (!running_.exchange(false)) return;
  wake_.notify();
  if (thread_.joinable()) thread_.join();
}

void Pipeline::on_sample(const ImuSample& sample) {
  if (sample.sensor_id >= slots_.size()) return;
  Slot& s = *slots_[sample.sensor_id];
  if (!s.ring.try_push(sample)) s.drops.fetch_add(1, std::memory_order_relaxed);
  // Frames are built on the frame tick from the latest state, so the pipeline need not wake
  // for every sample (20 sensors at 1 kHz would cost 20 000 wake-ups a second): it drains on
  // the tick, or early when a ring is half full. Lowest-latency mode wakes it every time.
  if (cfg_.publish_every_sample || s.ring.size() >= kRingCapacity / 2) wake_.notify();
}

void Pipeline::on_raw(uint16_t device_index, int64_t t_host_ns, std::span<const uint8_t> bytes) {
  with_tap([&](outputs::RecordTap& t) { t.on_raw(device_index, t_host_ns, bytes); });
}

void Pipeline::on_connection(uint16_t device_index, bool connected, std::string_view reason) {
  if (device_index < device_sensor_.size()) {
    const int s = device_sensor_[device_index];
    if (s >= 0 && s < static_cast<int>(slots_.size()))
      slots_[s]->connected.store(connected ? 1 : 0);
  }
  if (!connected)
    log_.warn("device %u disconnected: %.*s", device_index, static_cast<int>(reason.size()),
              reason.data());
}

void Pipeline::on_reset_request(uint16_t device_index, ResetRequest what) {
  log_.info("device %u asked for a %s reset", device_index,
            what == ResetRequest::full ? "full (calibration)" : "heading");
  if (what == ResetRequest::full)
    calibrate(reset_pose_);
  else
    reset_heading();
}

void Pipeline::set_device_sensor(uint16_t device_index, int sensor) {
  if (device_index >= device_sensor_.size()) device_sensor_.resize(device_index + 1, -1);
  device_sensor_[device_index] = sensor;
}

void Pipeline::calibrate(CalibrationPose pose, bool mounting_motion) {
  std::lock_guard lock(cmd_mu_);
  commands_.push_back(
      {.kind = Command::calibrate, .pose = pose, .mounting_motion = mounting_motion});
  wake_.notify();
}

void Pipeline::reset_heading() {
  std::lock_guard lock(cmd_mu_);
  commands_.push_back({Command::reset_heading});
  wake_.notify();
}

void Pipeline::set_frame_flag(uint32_t flag, bool on) {
  std::lock_guard lock(cmd_mu_);
  commands_.push_back({.kind = Command::flag, .flag_bits = flag, .on = on});
  wake_.notify();
}

void Pipeline::set_record_tap(outputs::RecordTap* tap) {
  tap_.store(tap);
  // Wait for callers that may still hold the previous tap.
  while (tap_users_.load() != 0)
    std::this_thread::yield();
}

void Pipeline::set_device_counters(int sensor, uint32_t drops, uint32_t errors) {
  if (sensor < 0 || sensor >= static_cast<int>(slots_.size())) return;
  slots_[sensor]->dev_drops.store(drops, std::memory_order_relaxed);
  slots_[sensor]->dev_errors.store(errors, std::memory_order_relaxed);
}

PipelineStatus Pipeline::status() const {
  PipelineStatus st;
  {
    std::lock_guard lock(status_mu_);
    st = status_;
  }
  std::lock_guard lock(telemetry_mu_);
  st.telemetry = telemetry_;
  return st;
}

void Pipeline::on_telemetry(uint16_t sensor_id, const SensorTelemetry& telemetry) {
  if (sensor_id >= telemetry_.size()) return;
  std::lock_guard lock(telemetry_mu_);
  telemetry_[sensor_id] = telemetry;
}

uint64_t Pipeline::ring_drops() const {
  uint64_t n = 0;
  for (const auto& s : slots_)
    n += s->drops.load(std::memory_order_relaxed);
  return n;
}

void Pipeline::TapSink::on_frame(const PoseFrame& f) {
  p_.with_tap([&](outputs::RecordTap& t) { t.on_frame(f); });
}

void Pipeline::apply_commands(int64_t now_ns) {
  {
    std::unique_lock lock(cmd_mu_, std::try_to_lock);
    if (!lock.owns_lock() || commands_.empty()) return;
    commands_work_.swap(commands_);
  }
  for (const Command& c : commands_work_) {
    switch (c.kind) {
      case Command::calibrate:
        core_.request_calibration(c.pose, now_ns, c.mounting_motion);
        break;
      case Command::reset_heading:
        core_.reset_heading();
        break;
      case Command::flag:
        core_.set_frame_flag(c.flag_bits, c.on);
        break;
    }
  }
  commands_work_.clear();
}

void Pipeline::drain() {
  // Take what each ring holds now, then merge the per-sensor runs by host timestamp.
  const size_t n = slots_.size();
  for (size_t i = 0; i < n; ++i) {
    size_t k = 0;
    while (k < kRingCapacity && slots_[i]->ring.try_pop(scratch_[i][k]))
      ++k;
    scratch_n_[i] = k;
    scratch_pos_[i] = 0;
  }
  for (;;) {
    int best = -1;
    int64_t best_t = INT64_MAX;
    for (size_t i = 0; i < n; ++i) {
      if (scratch_pos_[i] < scratch_n_[i] && scratch_[i][scratch_pos_[i]].t_host_ns < best_t) {
        best_t = scratch_[i][scratch_pos_[i]].t_host_ns;
        best = static_cast<int>(i);
      }
    }
    if (best < 0) break;
    const ImuSample& s = scratch_[best][scratch_pos_[best]++];
    with_tap([&](outputs::RecordTap& t) { t.on_sample(s); });
    core_.process(s);
  }
}

void Pipeline::snapshot() {
  std::unique_lock lock(status_mu_, std::try_to_lock);
  if (!lock.owns_lock()) return;  // a status reader holds it: skip, next frame will do
  status_.frame = core_.last_frame();
  status_.calibration = core_.calibration_progress();
  status_.samples = core_.samples_processed();
  status_.rejected = core_.rejected_samples();
  status_.ring_drops = ring_drops();
  status_.frames = core_.last_frame().frame;
  status_.calibrating = (core_.last_frame().flags & kFrameCalibrating) != 0;
}

void Pipeline::publish(int64_t now_ns) {
  for (size_t i = 0; i < slots_.size(); ++i) {
    const Slot& s = *slots_[i];
    core_.set_external_counters(static_cast<int>(i),
                                static_cast<uint32_t>(s.drops.load(std::memory_order_relaxed) +
                                                      s.dev_drops.load(std::memory_order_relaxed)),
                                s.dev_errors.load(std::memory_order_relaxed));
    const int c = s.connected.load(std::memory_order_relaxed);
    if (c >= 0) core_.set_connected(static_cast<int>(i), c == 1);
  }
  // The wall clock beside the monotonic one (sampled back to back), for the frames' t_unix_ns.
  core_.set_unix_offset_ns(realtime_ns() - monotonic_ns());
  core_.publish_frame(now_ns);
  snapshot();
}

void Pipeline::run() {
  // Keep signals for the main thread.
  sigset_t all;
  sigfillset(&all);
  pthread_sigmask(SIG_BLOCK, &all, nullptr);
  std::string rt_error;
  if (!set_this_thread_realtime(cfg_.realtime_priority, &rt_error))
    log_.warn("%s", rt_error.c_str());
  const int64_t period = static_cast<int64_t>(std::llround(1e9 / cfg_.rate_hz));
  int64_t next_frame = monotonic_ns() + period;
  core_.set_unix_offset_ns(realtime_ns() - monotonic_ns());
  while (running_.load(std::memory_order_relaxed)) {
    wait_until(wake_.fd(), next_frame);
    wake_.wait(0);  // clear pending notifications
    const int64_t now = monotonic_ns();
    apply_commands(now);
    drain();
    if (cfg_.publish_every_sample) snapshot();
    if (now >= next_frame) {
      publish(now);
      next_frame += period;
      if (next_frame < now) next_frame = now + period;  // we fell behind: skip, don't burst
    }
  }
  drain();
}

}  // namespace mocap::daemon
