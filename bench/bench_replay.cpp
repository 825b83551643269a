// mocap bench replay: a long recorded session (default 60 min, 17 sensors at 100 Hz = 6.1 M
// samples) replayed offline exactly as `mocap replay SESSION --bvh OUT` runs it (a child process
// of this binary: session reader -> filter per sensor -> calibration -> skeleton -> BVH file).
// The session is generated first from the virtual performer (not timed): its 15 sensors plus 2
// unattached sensors carrying copies of the pelvis and torso samples, to make 17. Baseline in
// the same process: reading and decoding every sample of the same file, nothing else.
#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench.hpp"
#include "daemon_harness.hpp"
#include "mocap/core/cli.hpp"
#include "mocap/core/time.hpp"
#include "mocap/daemon/config.hpp"
#include "mocap/daemon/replay.hpp"
#include "mocap/session/session_writer.hpp"
#include "mocap/sim/performer.hpp"

namespace mocap::bench {

namespace {

using namespace mocap::daemon;

constexpr int kExtraSensors = 2;  // copies of performer sensors 0 and 1 (unattached)

/// Writes the session; returns the number of samples; fills the N-pose time of the motion.
uint64_t generate_session(const std::string& path, double minutes, double rate_hz,
                          double& npose_at_s) {
  sim::PerformerParams pp;
  pp.rate_hz = rate_hz;
  pp.loop = true;
  sim::Performer performer(pp);
  const auto win = performer.calibration_window_s();
  npose_at_s = 0.5 * (win.first + win.second);
  ConfigErrors errs;
  Config cfg = *parse_config("", "<bench>", {}, errs);
  session::SessionHeader h;
  const int n = sim::Performer::kSensorCount + kExtraSensors;
  for (int i = 0; i < n; ++i) {
    SensorConfig s;
    s.name = i < sim::Performer::kSensorCount ? std::string(sim::Performer::sensor_name(i))
                                              : "extra_" + std::to_string(i);
    if (i < sim::Performer::kSensorCount) s.segment = s.name;
    s.driver = "witmotion";
    s.port = "/dev/null";
    s.rate_hz = rate_hz;
    cfg.sensors.push_back(s);
    session::SensorDescription d;
    d.name = s.name;
    d.protocol = s.driver;
    d.device_index = static_cast<uint16_t>(i);
    h.sensors.push_back(d);
  }
  h.config_text = config_to_toml(cfg);
  SessionWriter::Options wo;
  wo.buffer_bytes = 32u << 20;
  wo.flush_interval_ms = 200;
  std::string err;
  auto w = SessionWriter::create(path, h, wo, &err);
  if (!w) throw std::runtime_error(err);
  std::vector<ImuSample> batch;
  batch.reserve(4096);
  const int64_t end_ns = static_cast<int64_t>(minutes * 60e9);
  const int64_t step_ns = 100'000'000;
  uint64_t count = 0;
  auto append = [&](const ImuSample& s) {
    while (!w->append_sample(s))
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    ++count;
  };
  for (int64_t t = step_ns; t <= end_ns + step_ns / 2; t += step_ns) {
    batch.clear();
    performer.step_to(std::min(t, end_ns), batch);
    for (const ImuSample& s : batch) {
      append(s);
      if (s.sensor_id < kExtraSensors) {
        ImuSample c = s;
        c.sensor_id = static_cast<uint16_t>(sim::Performer::kSensorCount + s.sensor_id);
        append(c);
      }
    }
  }
  if (!w->close()) throw std::runtime_error(path + ": " + w->stats().error);
  return count;
}

/// mocap bench replay's command line (declared in add_replay).
struct ReplayBenchOptions {
  double minutes = 60, rate_hz = 100;
  std::string dir = "/tmp";
  std::string session;  ///< keep the session here (generated unless it exists)
};

int run_replay(const ReplayBenchOptions& o) {
  const double minutes = o.minutes, rate = o.rate_hz;
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(o.dir) / ("mocap-bench-replay-" + std::to_string(::getpid()));
  std::error_code ec;
  fs::create_directories(dir, ec);
  const bool keep = !o.session.empty();
  const std::string session = keep ? o.session : (dir / "session.mocapses").string();
  const std::string bvh = (dir / "out.bvh").string();
  const double load_before = load_average_1m();
  int rc = 0;
  try {
    double npose_at_s = 0;
    const int64_t g0 = monotonic_ns();
    const bool reuse = keep && fs::exists(session);
    const uint64_t generated = reuse ? 0 : generate_session(session, minutes, rate, npose_at_s);
    const double gen_s = (monotonic_ns() - g0) * 1e-9;
    const uint64_t session_bytes = fs::file_size(session);
    // Baseline: read + decode every sample of the file (the replay's input stage alone).
    const int64_t b0 = monotonic_ns();
    uint64_t baseline_samples = 0;
    {
      auto src = open_sample_source(session, nullptr);
      ImuSample s;
      while (src->next(s))
        ++baseline_samples;
      if (!src->error().empty()) throw std::runtime_error(src->error());
    }
    const double baseline_s = (monotonic_ns() - b0) * 1e-9;
    const uint64_t expected = reuse ? baseline_samples : generated;
    // The replay, as the user runs it.
    const std::string self = fs::read_symlink("/proc/self/exe").string();
    (void)npose_at_s;
    const std::string cmd = "'" + self + "' replay '" + session + "' --bvh '" + bvh + "' --quiet";
    rusage ru0{};
    ::getrusage(RUSAGE_CHILDREN, &ru0);
    const int64_t r0 = monotonic_ns();
    FILE* p = ::popen(cmd.c_str(), "r");
    if (!p) throw std::runtime_error("cannot run " + cmd);
    std::string out;
    char buf[4096];
    while (size_t n = std::fread(buf, 1, sizeof buf, p))
      out.append(buf, n);
    const int status = ::pclose(p);
    const double replay_s = (monotonic_ns() - r0) * 1e-9;
    rusage ru1{};
    ::getrusage(RUSAGE_CHILDREN, &ru1);
    auto secs = [](const timeval& t) { return t.tv_sec + t.tv_usec * 1e-6; };
    const double replay_cpu_s =
        secs(ru1.ru_utime) + secs(ru1.ru_stime) - secs(ru0.ru_utime) - secs(ru0.ru_stime);
    if (status != 0) throw std::runtime_error("'" + cmd + "' failed: " + out);
    const auto j = nlohmann::json::parse(out);
    const uint64_t replayed = j.at("samples").get<uint64_t>();
    const uint64_t bvh_bytes = fs::file_size(bvh);
    const double goal_s = 4.0 * minutes / 60.0;
    const bool pass = replayed == expected && replay_s <= goal_s;
    std::printf(
        "{\"benchmark\":\"replay\",\"command\":\"%s replay SESSION --bvh OUT --quiet\",\n"
        " \"params\":{\"minutes\":%g,\"sensors\":%d,\"rate_hz\":%g},\n"
        " \"samples\":{\"generated\":%llu,\"baseline_read\":%llu,\"replayed\":%llu},"
        "\"frames\":%llu,\"session_mb\":%.1f,\"bvh_mb\":%.1f,\"generate_s\":%.2f,\n"
        " \"replay_s\":%.3f,\"replay_cpu_s\":%.3f,\"replay_inner_s\":%.3f,\"samples_per_s\":%.0f,\n"
        " \"baseline_read_s\":%.3f,\"ratio_to_baseline\":%.2f,\n"
        " \"goal\":{\"seconds\":%.2f,\"note\":\"4 s per 60 min, scaled with --minutes\"},"
        "\"pass\":%s,\n"
        " \"load_average_1m\":{\"before\":%.2f,\"after\":%.2f}}\n",
        self.c_str(), minutes, sim::Performer::kSensorCount + kExtraSensors, rate,
        static_cast<unsigned long long>(expected),
        static_cast<unsigned long long>(baseline_samples),
        static_cast<unsigned long long>(replayed), j.value("frames", 0ull), session_bytes / 1e6,
        bvh_bytes / 1e6, gen_s, replay_s, replay_cpu_s, j.value("wall_s", -1.0),
        replayed / replay_s, baseline_s, replay_s / baseline_s, goal_s, pass ? "true" : "false",
        load_before, load_average_1m());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mocap bench replay: %s\n", e.what());
    rc = 1;
  }
  fs::remove_all(dir, ec);
  return rc;
}

}  // namespace

void add_replay(CLI::App& bench, int& exit_code) {
  auto o = std::make_shared<ReplayBenchOptions>();
  CLI::App* c = cli::add_command(
      bench, "replay", "a long recorded session through filter, skeleton and BVH, vs reading it");
  c->add_option("--minutes", o->minutes, "session length, minutes")->check(CLI::PositiveNumber);
  c->add_option("--rate", o->rate_hz, "sample rate per sensor, Hz")
      ->check(CLI::Range(1e-9, 1000.0));
  c->add_option("--dir", o->dir, "where to write the session and BVH; removed afterwards");
  c->add_option("--session", o->session,
                "keep the session in this file (used as it is if it exists: --minutes and "
                "--rate must match it)");
  c->callback([o, &exit_code] { exit_code = run_replay(*o); });
}

}  // namespace mocap::bench
