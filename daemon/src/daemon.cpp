// Daemon assembly: devices feed the pipeline, the pipeline feeds the outputs, the control
// socket drives commands and reports status as JSON.
#include "mocap/daemon/daemon.hpp"

#include <poll.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "mocap/core/segments.hpp"
#include "mocap/core/time.hpp"
#include "mocap/outputs/json_stream.hpp"
#include "mocap/rig/body_tracker.hpp"

namespace mocap::daemon {

std::vector<SensorInfo> sensor_infos(const Config& cfg) {
  std::vector<SensorInfo> out;
  for (const auto& s : cfg.sensors) {
    SensorInfo i;
    i.name = s.name;
    if (auto seg = segment_from_name(s.segment)) i.segment = index(*seg);
    out.push_back(i);
  }
  return out;
}

namespace {
/// Drivers whose sensors on one port share a device (one socket / one receiver dongle).
bool shared_port_driver(const std::string& d) {
  return d == "slimevr" || d == "slimevr_hid";
}
}  // namespace

size_t device_leader(const Config& cfg, size_t i) {
  const SensorConfig& s = cfg.sensors.at(i);
  if (!shared_port_driver(s.driver)) return i;
  for (size_t j = 0; j < i; ++j) {
    const SensorConfig& o = cfg.sensors[j];
    if (o.driver == s.driver && o.port == s.port && o.vid == s.vid && o.pid == s.pid &&
        o.serial == s.serial)
      return j;
  }
  return i;
}

DeviceSpec device_spec(const Config& cfg, size_t i) {
  const SensorConfig& s = cfg.sensors.at(i);
  DeviceSpec d;
  d.name = s.name;
  d.protocol = s.driver;
  if (!s.port.empty()) {
    d.port = s.port;
  } else {
    char ids[32];
    std::snprintf(ids, sizeof ids, "%04x:%04x", s.vid, s.pid);
    d.port = std::string(s.hid ? "hid:" : "usb:") + ids + (s.serial.empty() ? "" : ":" + s.serial);
  }
  d.baud = s.baud;
  d.rate_hz = s.rate_hz;
  d.device_index = static_cast<uint16_t>(i);
  d.first_sensor_id = static_cast<uint16_t>(i);
  d.axis_remap = s.axis_remap;
  d.options = s.options;
  d.realtime_priority = cfg.pipeline.realtime_priority;
  d.read_batch_ns = cfg.pipeline.publish_every_sample
                        ? 0
                        : static_cast<int64_t>(cfg.pipeline.read_batch_ms * 1e6);
  if (shared_port_driver(s.driver) && device_leader(cfg, i) == i) {
    // One socket for every tracker on this port: MAC/SENSOR=INDEX for each member.
    // (A lone sensor keeps its own options.mac/tracker, whose errors name those keys.)
    std::string map;
    size_t members = 0;
    for (size_t j = i; j < cfg.sensors.size(); ++j) {
      if (cfg.sensors[j].driver != s.driver || device_leader(cfg, j) != i) continue;
      const auto& o = cfg.sensors[j].options;
      const auto mac = o.find("mac"), id = o.find("tracker");
      map += (map.empty() ? "" : ";") + (mac == o.end() ? std::string("?") : mac->second) + "/" +
             (id == o.end() ? std::string("0") : id->second) + "=" + std::to_string(j) + "@" +
             cfg.sensors[j].axis_remap;
      ++members;
    }
    if (members > 1) d.options["trackers"] = map;
  }
  return d;
}

Daemon::Daemon(Config cfg, Parts parts, Logger log)
    : cfg_(std::move(cfg)), parts_(std::move(parts)), log_(std::move(log)) {
  if (!parts_.engine) throw std::invalid_argument("daemon needs a pose engine");
  pipeline_ = std::make_unique<Pipeline>(cfg_.pipeline, cfg_.calibration, sensor_infos(cfg_),
                                         *parts_.engine, log_.child("pipeline", log_.level()));
  for (auto& s : parts_.sinks)
    pipeline_->add_sink(s.get());
  control_path_ =
      cfg_.daemon.control_socket.empty() ? default_control_socket() : cfg_.daemon.control_socket;
}

Daemon::~Daemon() {
  shutdown();
}

void Daemon::start() {
  started_ns_ = monotonic_ns();
  if (parts_.frame_flags) {
    for (uint32_t bit = 1; bit; bit <<= 1)
      if (parts_.frame_flags & bit) pipeline_->set_frame_flag(bit, true);
  }
  pipeline_->start();
  running_ = true;
  for (auto& s : parts_.services)
    s->start(*pipeline_);
  if (parts_.device_factory) {
    for (size_t i = 0; i < cfg_.sensors.size(); ++i) {
      if (device_leader(cfg_, i) != i) continue;  // a SlimeVR tracker: its port's device
      const auto& s = cfg_.sensors[i];
      auto dev = parts_.device_factory(device_spec(cfg_, i), log_.child(s.name, s.log_level));
      dev->start(*pipeline_);
      devices_.push_back(std::move(dev));
    }
  }
  control_ = std::make_unique<ControlServer>(
      control_path_, [this](const ControlRequest& r) { return handle(r); },
      log_.child("control", log_.level()));
  if (!cfg_.recording.auto_start.empty()) {
    // A fresh name at every start (name-2.ext, ...): a restart never truncates a take.
    ControlRequest r{ControlCommand::record_start, cfg_.recording.auto_start, true};
    const std::string reply = handle(r);
    if (reply.find("\"ok\":false") != std::string::npos)
      throw std::runtime_error("recording.auto_start: " + reply);
  }
  log_.info("running: %zu sensors, %.0f Hz frames, control socket %s", cfg_.sensors.size(),
            cfg_.pipeline.rate_hz, control_path_.c_str());
}

void Daemon::wait(int extra_fd) {
  for (;;) {
    pollfd fds[2] = {{stop_.fd(), POLLIN, 0}, {extra_fd, POLLIN, 0}};
    const int n = ::poll(fds, extra_fd >= 0 ? 2 : 1, 500);
    if (n > 0 && (fds[0].revents & POLLIN)) return;
    if (n > 0 && extra_fd >= 0 && (fds[1].revents & POLLIN)) return;
    update_device_counters();
    if (parts_.recorder) {
      // Under rec_mu_: the control thread replaces the recorder's writer on record start/stop.
      std::lock_guard lock(rec_mu_);
      const std::string err = parts_.recorder->error();
      if (!err.empty() && !recording_path_.empty()) {
        log_.error("recording %s stopped: %s", recording_path_.c_str(), err.c_str());
        pipeline_->set_record_tap(nullptr);
        parts_.recorder->stop();
        pipeline_->set_frame_flag(kFrameRecording, false);
        recording_path_.clear();
      }
    }
  }
}

void Daemon::update_device_counters() {
  for (size_t i = 0; i < devices_.size(); ++i) {
    const DeviceStats st = devices_[i]->stats();
    pipeline_->set_device_counters(
        static_cast<int>(devices_[i]->spec().device_index),
        static_cast<uint32_t>(st.decoder.dropped_samples),
        static_cast<uint32_t>(st.decoder.checksum_errors + st.decoder.resyncs));
  }
}

void Daemon::shutdown() {
  if (!running_) return;
  running_ = false;
  control_.reset();
  for (auto& d : devices_)
    d->stop();
  // Services (the demo's performer) feed the pipeline: stopped before it, as devices are (they
  // were only stopped by their destructors, after the pipeline was gone: a crash on quit).
  for (auto& s : parts_.services)
    s->stop();
  pipeline_->stop();
  std::lock_guard lock(rec_mu_);
  if (!recording_path_.empty() && parts_.recorder) {
    pipeline_->set_record_tap(nullptr);
    parts_.recorder->stop();
    log_.info("recording %s closed", recording_path_.c_str());
    recording_path_.clear();
  }
  devices_.clear();
}

std::string Daemon::handle(const ControlRequest& r) {
  nlohmann::json ok{{"ok", true}};
  switch (r.command) {
    case ControlCommand::status:
      return status_json();
    case ControlCommand::calibrate: {
      // No pose named: the configured one (calibration.pose).
      const std::string pose =
          r.argument.empty() ? std::string(to_string(cfg_.calibration.pose)) : r.argument;
      const bool mounting = pose == "mounting";
      pipeline_->calibrate(pose == "tpose" ? CalibrationPose::tpose : CalibrationPose::npose,
                           mounting);
      const std::string in =
          std::to_string(static_cast<int>(std::lround(cfg_.calibration.countdown_s))) + " s";
      ok["message"] = mounting
                          ? "mounting calibration in " + in +
                                ": hold the N-pose, then bow and bend the knees twice, curling the "
                                "elbows, within " +
                                std::to_string(static_cast<int>(
                                    std::lround(rig::TrackerOptions{}.mounting_motion_s))) +
                                " s"
                          : "calibration (" + pose + ") in " + in + ": hold the pose";
      return ok.dump();
    }
    case ControlCommand::reset_heading:
      pipeline_->reset_heading();
      ok["message"] = "heading reset";
      return ok.dump();
    case ControlCommand::record_start: {
      if (!parts_.recorder) return control_error_reply("recording is not available in this build");
      std::lock_guard lock(rec_mu_);
      if (!recording_path_.empty())
        return control_error_reply("already recording to " + recording_path_);
      outputs::RecordTap* tap = parts_.recorder->start(r.argument, r.unique);
      pipeline_->set_record_tap(tap);
      pipeline_->set_frame_flag(kFrameRecording, true);
      recording_path_ = parts_.recorder->path();
      log_.info("recording to %s", recording_path_.c_str());
      ok["file"] = recording_path_;
      return ok.dump();
    }
    case ControlCommand::record_stop: {
      std::lock_guard lock(rec_mu_);
      if (recording_path_.empty() || !parts_.recorder) return control_error_reply("not recording");
      pipeline_->set_record_tap(nullptr);
      const outputs::RecordingSummary sum = parts_.recorder->stop();
      pipeline_->set_frame_flag(kFrameRecording, false);
      ok["file"] = recording_path_;
      ok["duration_s"] = std::round(sum.duration_s * 1000) / 1000;
      ok["frames"] = sum.frames;
      ok["samples"] = sum.samples;
      ok["raw_blocks"] = sum.raw_blocks;
      ok["drops"] = sum.drops;
      ok["bytes"] = sum.bytes;
      if (!sum.error.empty()) ok["error"] = sum.error;
      char msg[160];
      std::snprintf(
          msg, sizeof msg,
          "recorded %.1f s: %llu frames, %llu samples, %llu dropped, %llu bytes in", sum.duration_s,
          static_cast<unsigned long long>(sum.frames), static_cast<unsigned long long>(sum.samples),
          static_cast<unsigned long long>(sum.drops), static_cast<unsigned long long>(sum.bytes));
      ok["message"] = msg;
      log_.info("recording %s closed", recording_path_.c_str());
      recording_path_.clear();
      return ok.dump();
    }
    case ControlCommand::quit:
      request_stop();
      ok["message"] = "stopping";
      return ok.dump();
  }
  return control_error_reply("unhandled command");
}

namespace {
/// What the sensor reported about itself, as far as it did (docs/streaming.md, status).
void add_telemetry(const SensorTelemetry& t, nlohmann::json& e) {
  const auto num = [&](const char* key, float v, double per_unit) {
    if (SensorTelemetry::known(v))
      e[key] = std::round(static_cast<double>(v) * per_unit) / per_unit;
  };
  num("battery_pct", t.battery_fraction * 100.0f, 1);
  num("battery_v", t.battery_v, 100);
  num("battery_runtime_s", t.battery_runtime_s, 1);
  num("rssi_dbm", t.rssi_dbm, 1);
  num("temperature_c", t.temperature_c, 10);
  num("packet_loss_pct", t.packet_loss * 100.0f, 10);
  const auto text = [&](const char* key, const auto& field) {
    if (field[0] != 0) e[key] = std::string(field, strnlen(field, sizeof field));
  };
  text("board", t.board);
  text("imu", t.imu);
  text("mcu", t.mcu);
  text("firmware", t.firmware);
  text("address", t.address);
}
}  // namespace

std::string Daemon::status_json() const {
  static constexpr const char* kStates[] = {"absent", "connecting", "streaming",
                                            "stale",  "error",      "disconnected"};
  const PipelineStatus st = pipeline_->status();
  nlohmann::json j;
  j["ok"] = true;
  // Numbers rounded to what they mean (ms, 0.1 s): never 0.30000000000000004.
  const auto round_to = [](double v, double per_unit) {
    return std::round(v * per_unit) / per_unit;  // the nearest double to the decimal
  };
  j["uptime_s"] = round_to(ns_to_s(monotonic_ns() - started_ns_), 1000);
  j["frame"] = st.frame.frame;
  j["samples"] = st.samples;
  j["rejected_samples"] = st.rejected;
  j["ring_drops"] = st.ring_drops;
  j["rate_hz"] = cfg_.pipeline.rate_hz;
  j["calibrated"] = (st.frame.flags & kFrameCalibrated) != 0;
  j["calibrating"] = (st.frame.flags & kFrameCalibrating) != 0;
  j["calib_countdown_s"] = round_to(st.frame.calib_countdown_s, 10);
  j["demo"] = (st.frame.flags & kFrameDemo) != 0;
  {
    const CalibrationProgress& c = st.calibration;
    nlohmann::json cal;
    cal["message"] = std::string(c.message.data(), strnlen(c.message.data(), c.message.size()));
    cal["mounting_motion"] = c.mounting_motion;
    j["calibration"] = cal;
  }
  {
    std::lock_guard lock(rec_mu_);
    j["recording"] = recording_path_;
  }
  {
    // Where to reach this daemon: the streams (a port 0 JSON stream: the port it picked) and
    // the control socket.
    const OutputsConfig& o = cfg_.outputs;
    nlohmann::json streams;
    streams["json"] = {
        {"enabled", o.json.enabled},
        {"bind", o.json.bind},
        {"port", o.json.enabled ? outputs::json_stream_port(parts_.sinks) : o.json.port}};
    streams["vmc"] = {{"enabled", o.vmc.enabled}, {"host", o.vmc.host}, {"port", o.vmc.port}};
    streams["vrchat"] = {
        {"enabled", o.vrchat.enabled}, {"host", o.vrchat.host}, {"port", o.vrchat.port}};
    streams["control_socket"] = control_path_;
    j["streams"] = streams;
  }
  nlohmann::json sensors = nlohmann::json::array();
  for (uint32_t i = 0; i < st.frame.sensor_count && i < static_cast<uint32_t>(kMaxSensors); ++i) {
    const SensorStatus& s = st.frame.sensors[i];
    nlohmann::json e;
    e["name"] = std::string(s.name, strnlen(s.name, sizeof s.name));
    e["segment"] = s.segment >= 0 ? std::string(kSegmentNames[s.segment]) : std::string();
    e["state"] = s.state < std::size(kStates) ? kStates[s.state] : "error";
    // The status fields are floats: rounded as doubles, so 2.8 prints as 2.8.
    e["rate_hz"] = round_to(s.rate_hz, 10);
    e["age_ms"] = round_to(s.last_age_ms, 10);
    e["drops"] = s.drops;
    e["errors"] = s.errors;
    // Its device: its own, or the one its port's SlimeVR trackers share (device_leader).
    const size_t leader = i < cfg_.sensors.size() ? device_leader(cfg_, i) : i;
    const auto dev = std::find_if(devices_.begin(), devices_.end(),
                                  [&](const auto& d) { return d->spec().device_index == leader; });
    if (dev != devices_.end()) {
      const DeviceStats ds = (*dev)->stats();
      e["clock_resets"] = ds.decoder.clock_resets;  // device clock jumps/restarts detected
      e["reconnects"] = ds.reconnects;
      // Readings beyond the sensor's range (field dropped) / at full scale (docs/devices.md).
      e["implausible"] = ds.decoder.implausible;
      e["saturated"] = ds.decoder.saturated;
    }
    e["at_rest"] = (s.flags & kSegAtRest) != 0;
    e["mag_disturbed"] = (s.flags & kSegMagDisturbed) != 0;
    e["mag_no_reference"] = (s.flags & kSegMagNoReference) != 0;
    e["calibrated"] = (s.flags & kSegCalibrated) != 0;
    e["gyro_bias_dps"] = round_to(s.gyro_bias_dps, 1000);
    e["heading_sigma_deg"] = round_to(s.heading_sigma_deg, 10);
    // Its segment's alignment: where mounting and heading came from and how sure each is.
    if (s.segment >= 0 && s.segment < kSegmentCount) {
      const SegmentAlignmentStatus& a = st.calibration.segments[static_cast<size_t>(s.segment)];
      e["mounting"] = {{"source", rig::to_string(a.mounting_source)},
                       {"sigma_deg", round_to(a.mounting_sigma_deg, 10)}};
      e["alignment_heading"] = {{"source", rig::to_string(a.heading_source)},
                                {"sigma_deg", round_to(a.heading_sigma_deg, 10)},
                                {"rejected_turns", a.rejected_turns},
                                {"corrected_turns", a.corrected_turns},
                                {"lost", a.heading_lost},
                                {"lost_count", a.lost_headings}};
    }
    add_telemetry(st.telemetry[i], e);
    sensors.push_back(e);
  }
  j["sensors"] = sensors;
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace mocap::daemon
