// Replay: sample sources (session files, CSV) and the deterministic replay loop.
#include "mocap/daemon/replay.hpp"

#include <algorithm>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <thread>

#include "mocap/core/segments.hpp"
#include "mocap/core/time.hpp"
#include "mocap/daemon/daemon.hpp"
#include "mocap/daemon/sample_csv.hpp"
#include "mocap/daemon/text_lines.hpp"
#include "mocap/drivers/device.hpp"
#include "mocap/session/session_reader.hpp"

namespace mocap::daemon {

namespace {

/// Collects decoded samples of one feed() call.
struct QueueSink final : SampleSink {
  std::deque<ImuSample>* q = nullptr;
  void on_sample(const ImuSample& s) override { q->push_back(s); }
};

class SessionSourceImpl final : public SampleSource {
 public:
  SessionSourceImpl(const std::string& path, const Config* rig, SessionSource source)
      : path_(path) {
    std::string err;
    if (!reader_.open(path, &err)) throw std::runtime_error(err);
    const auto& h = reader_.header();
    ConfigErrors errs;
    if (rig) {
      cfg_ = *rig;
    } else {
      auto c = parse_config(h.config_text, path + " (recorded config)", {}, errs);
      if (!c) throw std::runtime_error(errs.to_string());
      cfg_ = *c;
    }
    // Recorded sensor i (device index d) -> rig sensor index by name.
    for (const auto& d : h.sensors) {
      int idx = -1;
      for (size_t i = 0; i < cfg_.sensors.size(); ++i)
        if (cfg_.sensors[i].name == d.name) idx = static_cast<int>(i);
      if (idx < 0 && rig)
        throw std::runtime_error(path + ": recorded sensor '" + d.name + "' is not in the rig");
      if (d.device_index >= device_sensor_.size()) device_sensor_.resize(d.device_index + 1, -1);
      device_sensor_[d.device_index] = idx;
    }
    calib_text_ = h.calibration_text;
    // Which stream to replay: samples if the file has any (what the pipeline saw), else raw.
    use_raw_ = source == SessionSource::raw;
    if (source == SessionSource::automatic) use_raw_ = !has_sample_blocks(path);
    if (use_raw_) {
      for (size_t d = 0; d < device_sensor_.size(); ++d) {
        const int s = device_sensor_[d];
        if (s < 0) {
          decoders_.push_back(nullptr);
          continue;
        }
        if (device_leader(cfg_, static_cast<size_t>(s)) != static_cast<size_t>(s)) {
          decoders_.push_back(nullptr);  // a SlimeVR tracker: recorded under its port's device
          continue;
        }
        DeviceSpec spec = device_spec(cfg_, static_cast<size_t>(s));
        multi_sensor_.resize(decoders_.size() + 1, false);
        multi_sensor_.back() = spec.options.count("trackers") > 0;  // ids set by the decoder
        decoders_.push_back(make_decoder(spec));
      }
    }
    sink_.q = &queue_;
    std::ifstream f(path, std::ios::binary | std::ios::ate);
    size_ = std::max<uint64_t>(1, static_cast<uint64_t>(f.tellg()));
  }

  const Config& config() const override { return cfg_; }
  const std::string& error() const override { return error_; }
  double progress() const override { return static_cast<double>(reader_.tail_offset()) / size_; }
  bool unix_offset_ns(int64_t& out) const override {
    out = reader_.unix_offset_ns();
    return true;
  }
  std::string calibration_text() const override { return calib_text_; }

  bool next(ImuSample& out) override {
    for (;;) {
      if (!queue_.empty()) {
        out = queue_.front();
        queue_.pop_front();
        return true;
      }
      if (!reader_.next(block_)) {
        if (reader_.end() == SessionReader::End::corrupt)
          error_ = path_ + ": " + reader_.tail_reason();
        return false;
      }
      if (use_raw_ && block_.type == session::BlockType::raw) {
        if (block_.device_index < decoders_.size() && decoders_[block_.device_index])
          decoders_[block_.device_index]->feed(block_.raw, block_.t_host_ns, sink_);
        const bool multi =
            block_.device_index < multi_sensor_.size() && multi_sensor_[block_.device_index];
        if (!multi)
          for (auto& s : queue_)
            s.sensor_id = static_cast<uint16_t>(device_sensor_[block_.device_index]);
      } else if (!use_raw_ && block_.type == session::BlockType::sample) {
        const uint16_t d = block_.sample.sensor_id;
        if (d < device_sensor_.size() && device_sensor_[d] >= 0) {
          out = block_.sample;
          out.sensor_id = static_cast<uint16_t>(device_sensor_[d]);
          return true;
        }
      }
    }
  }

 private:
  static bool has_sample_blocks(const std::string& path) {
    SessionReader r;
    std::string err;
    if (!r.open(path, &err)) return false;
    SessionReader::Block b;
    for (int n = 0; n < 100000 && r.next(b); ++n)
      if (b.type == session::BlockType::sample) return true;
    return false;
  }

  std::string path_;
  SessionReader reader_;
  SessionReader::Block block_;
  Config cfg_;
  std::vector<int> device_sensor_;
  std::vector<std::unique_ptr<StreamDecoder>> decoders_;
  std::vector<bool> multi_sensor_;  // per device: its decoder stamps the rig's sensor ids
  std::deque<ImuSample> queue_;
  QueueSink sink_;
  bool use_raw_ = false;
  std::string calib_text_, error_;
  uint64_t size_ = 1;
};

class CsvSourceImpl final : public SampleSource {
 public:
  CsvSourceImpl(const std::string& path, const Config* rig) : path_(path), parser_(path) {
    // First pass: the sensor names (a rig needs them before the first sample).
    std::vector<std::string> names;
    {
      TextLines in(path);
      SampleCsvParser p(path);
      ImuSample s;
      std::string line;
      while (in.next(line)) {
        if (p.feed_line(line, s) < 0) throw std::runtime_error(p.error());
      }
      if (!in.error().empty()) throw std::runtime_error(in.error());
      names = p.sensors();
    }
    if (rig) {
      cfg_ = *rig;
      for (const auto& n : names) {
        auto it = std::find_if(cfg_.sensors.begin(), cfg_.sensors.end(),
                               [&](const SensorConfig& s) { return s.name == n; });
        if (it == cfg_.sensors.end())
          throw std::runtime_error(path + ": sensor '" + n + "' is not in the rig");
        map_.push_back(static_cast<int>(it - cfg_.sensors.begin()));
      }
    } else {
      ConfigErrors errs;
      cfg_ = *parse_config("", "<defaults>", {}, errs);
      for (const auto& n : names) {
        SensorConfig s;
        s.name = n;
        s.driver = "csv";
        s.port = path;
        if (segment_from_name(n)) s.segment = n;
        map_.push_back(static_cast<int>(cfg_.sensors.size()));
        cfg_.sensors.push_back(s);
      }
      if (cfg_.sensors.size() > static_cast<size_t>(kMaxSensors))
        throw std::runtime_error(path + ": more than " + std::to_string(kMaxSensors) + " sensors");
    }
    in_ = std::make_unique<TextLines>(path);
  }
  const Config& config() const override { return cfg_; }
  const std::string& error() const override { return error_; }
  double progress() const override {
    return static_cast<double>(in_->file_offset()) / static_cast<double>(in_->file_size());
  }
  bool next(ImuSample& out) override {
    while (in_->next(line_)) {
      const int r = parser_.feed_line(line_, out);
      if (r < 0) {
        error_ = parser_.error();
        return false;
      }
      if (r == 1) {
        out.sensor_id = static_cast<uint16_t>(map_[out.sensor_id]);
        return true;
      }
    }
    error_ = in_->error();
    return false;
  }

 private:
  std::string path_;
  SampleCsvParser parser_;
  Config cfg_;
  std::vector<int> map_;
  std::unique_ptr<TextLines> in_;
  std::string line_, error_;
};

}  // namespace

std::unique_ptr<SampleSource> open_session_source(const std::string& path, const Config* rig,
                                                  SessionSource source) {
  return std::make_unique<SessionSourceImpl>(path, rig, source);
}

std::unique_ptr<SampleSource> open_csv_source(const std::string& path, const Config* rig) {
  return std::make_unique<CsvSourceImpl>(path, rig);
}

std::unique_ptr<SampleSource> open_sample_source(const std::string& path, const Config* rig) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open");
  char magic[8] = {};
  in.read(magic, sizeof magic);
  if (in.gcount() == 8 && std::memcmp(magic, session::kMagic, 8) == 0)
    return open_session_source(path, rig);
  return open_csv_source(path, rig);
}

ReplayResult run_replay(SampleSource& src, PipelineCore& core, const ReplayOptions& opt) {
  if (opt.filter_threads > 0 && opt.speed <= 0 && core.engine().prefilter_allowed())
    return run_replay_parallel(src, core, opt);
  ReplayResult r;
  ImuSample s;
  bool first = true, calibration_pending = opt.calibrate_pose.has_value();
  int64_t wall0 = 0, last_progress = 0;
  const uint64_t frames0 = core.last_frame().frame;
  while (src.next(s)) {
    if (first) {
      r.t_first_ns = s.t_host_ns;
      wall0 = monotonic_ns();
      first = false;
      if (opt.on_first_sample) opt.on_first_sample(s.t_host_ns);
    }
    if (calibration_pending &&
        s.t_host_ns - r.t_first_ns >= static_cast<int64_t>(opt.calibrate_at_s * 1e9)) {
      core.request_calibration(*opt.calibrate_pose, s.t_host_ns, opt.calibrate_mounting_motion);
      calibration_pending = false;
    }
    if (opt.speed > 0) {
      const int64_t due = wall0 + static_cast<int64_t>((s.t_host_ns - r.t_first_ns) / opt.speed);
      const int64_t wait = due - monotonic_ns();
      if (wait > 0) std::this_thread::sleep_for(std::chrono::nanoseconds(wait));
    }
    if (int64_t off = 0; src.unix_offset_ns(off)) core.set_unix_offset_ns(off);
    core.advance_clock_to(s.t_host_ns);
    core.process(s);
    r.t_last_ns = s.t_host_ns;
    if ((++r.samples & 0x3FF) == 0) {
      if (opt.cancelled && opt.cancelled()) {
        r.cancelled = true;
        break;
      }
      const int64_t now = monotonic_ns();
      if (opt.progress && now - last_progress > 100'000'000) {
        opt.progress(src.progress());
        last_progress = now;
      }
    }
  }
  if (!src.error().empty()) throw std::runtime_error(src.error());
  if (opt.progress) opt.progress(1.0);
  r.frames = core.last_frame().frame - frames0;
  return r;
}

}  // namespace mocap::daemon
