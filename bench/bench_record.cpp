// mocap bench record: what zstd block compression (recording.compression) saves and costs. A
// real recording is made first (not timed): `mocapd --demo` (15 simulated WitMotion sensors at
// 100 Hz through ptys and the real drivers; raw bytes, samples and 120 Hz poses recorded) for
// --seconds, or the SESSION given. Its blocks are then appended again, all at once, to a
// SessionWriter per setting (none, zstd levels 1, 3, 9); baseline in the same run: none. Figures:
// file size ratio, the writer thread's CPU time and the producers' append time as ratios to
// the baseline, and the writer's CPU per recorded second. Appended at once, runs are packed
// 128 KiB at a time; live, the writer packs what one 50 ms flush round holds, so with --live the
// demo is also recorded with zstd (level 3) live and its bytes per recorded second compared.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "bench.hpp"
#include "mocap/core/cli.hpp"
#include "mocap/core/time.hpp"
#include "mocap/session/session_reader.hpp"
#include "mocap/session/session_writer.hpp"

namespace mocap::bench {

namespace {

namespace fs = std::filesystem;

/// Records `seconds` of `mocapd --demo` into dir/NAME with recording.compression; returns its
/// path.
std::string record_demo(const fs::path& dir, double seconds, const std::string& name,
                        const std::string& compression) {
  const std::string mocapd = (fs::read_symlink("/proc/self/exe").parent_path() / "mocapd").string();
  const std::string log = (dir / "mocapd.log").string();
  std::vector<std::string> args = {
      mocapd,        "--demo",
      "--set",       "daemon.control_socket=" + (dir / "ctl.sock").string(),
      "--set",       "outputs.json.enabled=false",
      "--set",       "outputs.posture.shm_name=/mocap-bench-record-" + std::to_string(::getpid()),
      "--set",       "recording.directory=" + dir.string(),
      "--set",       "recording.auto_start=" + name,
      "--set",       "recording.compression=" + compression,
      "--log-level", "warn"};
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    std::vector<char*> argv;
    for (auto& a : args)
      argv.push_back(a.data());
    argv.push_back(nullptr);
    if (!std::freopen(log.c_str(), "w", stderr)) _exit(126);
    ::execv(mocapd.c_str(), argv.data());
    _exit(127);
  }
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  ::kill(pid, SIGTERM);
  int status = 0;
  ::waitpid(pid, &status, 0);
  const std::string path = (dir / name).string();
  if (!fs::exists(path) || fs::file_size(path) < 1000)
    throw std::runtime_error("mocapd --demo recorded nothing (see " + log + ")");
  return path;
}

/// A recording's blocks in memory, in file order.
struct Blocks {
  session::SessionHeader header;
  struct Raw {
    uint16_t device;
    int64_t t_ns;
    std::vector<uint8_t> bytes;
  };
  std::vector<session::BlockType> order;
  std::vector<Raw> raws;
  std::vector<ImuSample> samples;
  std::vector<PoseFrame> poses;
  uint64_t bytes = 0;
  double duration_s = 0;
};

Blocks load(const std::string& path) {
  SessionReader r;
  std::string err;
  if (!r.open(path, &err)) throw std::runtime_error(err);
  Blocks b;
  b.header = r.header();
  SessionReader::Block k;
  int64_t t0 = -1, t1 = -1;
  while (r.next(k)) {
    int64_t t = -1;
    switch (k.type) {
      case session::BlockType::raw:
        b.raws.push_back({k.device_index, k.t_host_ns, {k.raw.begin(), k.raw.end()}});
        t = k.t_host_ns;
        break;
      case session::BlockType::sample:
        b.samples.push_back(k.sample);
        t = k.sample.t_host_ns;
        break;
      case session::BlockType::pose:
        b.poses.push_back(k.pose);
        t = k.pose.t_ns;
        break;
      default:
        continue;
    }
    b.order.push_back(k.type);
    if (t0 < 0) t0 = t;
    t1 = std::max(t1, t);
  }
  b.bytes = fs::file_size(path);
  b.duration_s = (t1 - t0) * 1e-9;
  return b;
}

struct Result {
  std::string name;
  uint64_t file_bytes = 0;
  double writer_cpu_s = 0;
  double append_s = 0;
  uint64_t dropped = 0;
};

Result write_all(const Blocks& b, const std::string& path, const std::string& name,
                 SessionWriter::Options o) {
  o.buffer_bytes = static_cast<std::size_t>(b.bytes * 2 + (16u << 20));  // never full
  std::string err;
  auto w = SessionWriter::create(path, b.header, o, &err);
  if (!w) throw std::runtime_error(err);
  std::size_t ir = 0, is = 0, ip = 0;
  const int64_t a0 = monotonic_ns();
  for (const session::BlockType t : b.order) {
    if (t == session::BlockType::raw) {
      const auto& r = b.raws[ir++];
      w->append_raw(r.device, r.t_ns, r.bytes);
    } else if (t == session::BlockType::sample) {
      w->append_sample(b.samples[is++]);
    } else {
      w->append_pose(b.poses[ip++]);
    }
  }
  const double append_s = (monotonic_ns() - a0) * 1e-9;
  if (!w->close()) throw std::runtime_error(w->stats().error);
  const auto st = w->stats();
  Result res;
  res.name = name;
  res.file_bytes = fs::file_size(path);
  res.writer_cpu_s = st.writer_cpu_ns * 1e-9;
  res.append_s = append_s;
  res.dropped = st.blocks_dropped;
  return res;
}

struct RecordBenchOptions {
  std::string session;  ///< empty: record the demo
  double seconds = 20, repeat = 3;
  std::string dir = "/tmp";
  bool live = false;
};

int run_record(const RecordBenchOptions& o) {
  const fs::path dir = fs::path(o.dir) / ("mocap-bench-record-" + std::to_string(::getpid()));
  std::error_code ec;
  fs::create_directories(dir, ec);
  int rc = 0;
  try {
    const std::string input =
        o.session.empty() ? record_demo(dir, o.seconds, "in.mocapses", "none") : o.session;
    const Blocks b = load(input);
    double live_ratio = 0, live_mb_per_hour = 0;
    if (o.live && o.session.empty()) {
      const Blocks z = load(record_demo(dir, o.seconds, "live.mocapses", "zstd"));
      const double plain_rate = b.bytes / b.duration_s, zstd_rate = z.bytes / z.duration_s;
      live_ratio = plain_rate / zstd_rate;
      live_mb_per_hour = zstd_rate * 3600 / 1e6;
    }
    struct Setting {
      const char* name;
      SessionWriter::Options::Compression c;
      int level;
    };
    const Setting settings[] = {{"none", SessionWriter::Options::Compression::none, 0},
                                {"zstd-1", SessionWriter::Options::Compression::zstd, 1},
                                {"zstd-3", SessionWriter::Options::Compression::zstd, 3},
                                {"zstd-9", SessionWriter::Options::Compression::zstd, 9}};
    std::vector<Result> results;
    for (const Setting& s : settings) {
      Result best;
      for (int k = 0; k < static_cast<int>(o.repeat); ++k) {
        SessionWriter::Options w;
        w.compression = s.c;
        w.compression_level = s.level;
        const Result r = write_all(b, (dir / "out.mocapses").string(), s.name, w);
        if (k == 0 || r.writer_cpu_s < best.writer_cpu_s) best = r;
      }
      results.push_back(best);
    }
    const Result& base = results[0];
    std::printf(
        "{\"benchmark\":\"record\",\"input\":{\"source\":\"%s\",\"recorded_s\":%.1f,"
        "\"blocks\":%zu,\"raw\":%zu,\"samples\":%zu,\"poses\":%zu,\"mb\":%.2f},\n"
        " \"baseline\":\"none\",\"settings\":[",
        o.session.empty() ? "mocapd --demo" : input.c_str(), b.duration_s, b.order.size(),
        b.raws.size(), b.samples.size(), b.poses.size(), b.bytes / 1e6);
    for (std::size_t i = 0; i < results.size(); ++i) {
      const Result& r = results[i];
      std::printf(
          "%s\n  {\"compression\":\"%s\",\"file_mb\":%.3f,\"size_ratio\":%.2f,"
          "\"mb_per_hour\":%.0f,\"writer_cpu_s\":%.3f,\"writer_cpu_ratio\":%.2f,"
          "\"writer_cpu_per_recorded_s_pct\":%.3f,\"append_ratio\":%.2f,\"dropped\":%llu}",
          i ? "," : "", r.name.c_str(), r.file_bytes / 1e6,
          static_cast<double>(base.file_bytes) / r.file_bytes,
          r.file_bytes / 1e6 * 3600 / b.duration_s, r.writer_cpu_s,
          r.writer_cpu_s / base.writer_cpu_s, 100 * r.writer_cpu_s / b.duration_s,
          r.append_s / base.append_s, static_cast<unsigned long long>(r.dropped));
    }
    std::printf("],\n \"live_zstd3\":{\"measured\":%s,\"size_ratio\":%.2f,\"mb_per_hour\":%.0f}}\n",
                live_ratio > 0 ? "true" : "false", live_ratio, live_mb_per_hour);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mocap bench record: %s\n", e.what());
    rc = 1;
  }
  fs::remove_all(dir, ec);
  return rc;
}

}  // namespace

void add_record(CLI::App& bench, int& exit_code) {
  auto o = std::make_shared<RecordBenchOptions>();
  CLI::App* c = cli::add_command(
      bench, "record",
      "session block compression (zstd levels vs none): size ratio and writer CPU");
  c->add_option("SESSION", o->session, "a recorded session to re-write (default: record the demo)");
  cli::add_deprecated_alias(
      *c, "--seconds", o->seconds,
      c->add_option("--duration", o->seconds, "length of the demo recording to make")
          ->check(CLI::Range(2.0, 3600.0)));
  c->add_option("--repeat", o->repeat, "write each setting this many times, keep the least CPU")
      ->check(CLI::Range(1.0, 20.0));
  c->add_option("--dir", o->dir, "where to write the files; removed afterwards");
  c->add_flag("--live", o->live,
              "also record the demo live with zstd and compare its size (no SESSION)");
  c->callback([o, &exit_code] { exit_code = run_record(*o); });
}

}  // namespace mocap::bench
