// mocap replay: runs a recorded session or a CSV of samples offline through the daemon's
// pipeline (filter -> calibration -> skeleton) and writes BVH and/or pose CSV.
//   mocap replay INPUT [--config RIG.toml] [--set K=V] [--bvh OUT.bvh] [--csv OUT.csv]
//                [--calibrate npose@SECONDS|tpose@SECONDS|mounting@SECONDS] [--source raw|samples]
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <thread>

#include "commands.hpp"
#include "mocap/core/cli.hpp"
#include "mocap/core/time.hpp"
#include "mocap/daemon/daemon.hpp"
#include "mocap/daemon/prefetch_source.hpp"
#include "mocap/daemon/replay_run.hpp"
#include "mocap/daemon/rig_engine.hpp"
#include "mocap/outputs/bvh_output.hpp"
#include "mocap/outputs/frame_writer_thread.hpp"
#include "mocap/outputs/poses_csv.hpp"
#include "run_summary.hpp"

namespace mocap::cmd {

namespace {

using namespace mocap::daemon;

bool parse_calibrate(const std::string& s, mocap::CalibrationPose& pose, bool& mounting,
                     double& at_s) {
  const auto at = s.find('@');
  if (at == std::string::npos) return false;
  const std::string p = s.substr(0, at);
  mounting = p == "mounting";
  if (p == "npose" || mounting)
    pose = mocap::CalibrationPose::npose;
  else if (p == "tpose")
    pose = mocap::CalibrationPose::tpose;
  else
    return false;
  char* end = nullptr;
  at_s = std::strtod(s.c_str() + at + 1, &end);
  return end && *end == '\0' && at + 1 < s.size() && at_s >= 0;
}

/// mocap replay's command line (declared in add_replay).
struct ReplayCommandOptions {
  std::string input, config, config_alias, bvh, csv, csv_alias, calibrate, source;
  std::vector<std::string> sets;
  bool quiet = false;
  int filter_threads = -1;  ///< -1: one fewer than the cores (at least 1)
};

int run_replay(const ReplayCommandOptions& o) {
  const std::string& input = o.input;
  const std::string rig_path = o.config.empty() ? o.config_alias : o.config;
  const std::string csv_path = o.csv.empty() ? o.csv_alias : o.csv;
  std::optional<Config> rig;
  const auto& sets = o.sets;
  if (!rig_path.empty()) {
    ConfigErrors errs;
    rig = load_config(rig_path, sets, errs, &default_validators());
    if (!rig) {
      std::fprintf(stderr, "%s", errs.to_string().c_str());
      return 1;
    }
  }
  ReplayOptions opt;
  opt.filter_threads = o.filter_threads >= 0
                           ? o.filter_threads
                           : std::max(1, static_cast<int>(std::thread::hardware_concurrency()) - 1);
  if (!o.calibrate.empty()) {
    mocap::CalibrationPose pose;
    parse_calibrate(o.calibrate, pose, opt.calibrate_mounting_motion,
                    opt.calibrate_at_s);  // checked by the option
    opt.calibrate_pose = pose;
  }
  const SessionSource which = o.source == "raw"       ? SessionSource::raw
                              : o.source == "samples" ? SessionSource::samples
                                                      : SessionSource::automatic;
  try {
    std::unique_ptr<SampleSource> src;
    if (!o.source.empty())
      src = open_session_source(input, rig ? &*rig : nullptr, which);
    else
      src = open_sample_source(input, rig ? &*rig : nullptr);
    // Read and decode the file on the other core while this one filters and solves.
    src = std::make_unique<PrefetchSource>(std::move(src));
    // --set without --config: applied to the input's own configuration.
    ReplayRun run(replay_config(*src, rig.has_value(), sets, input), *src, input,
                  !opt.calibrate_pose);
    const Config& cfg = run.cfg;
    RigEngine& engine = run.engine;
    PipelineCore& core = run.core;
    // Each file is formatted and written on a thread of its own, frames in order.
    std::unique_ptr<outputs::BvhOutput> bvh;
    std::unique_ptr<outputs::PosesCsvSink> poses;
    std::unique_ptr<outputs::FrameWriterThread> bvh_thread, poses_thread;
    if (!o.bvh.empty()) {
      bvh = std::make_unique<outputs::BvhOutput>(o.bvh, cfg.body.model, 1.0 / cfg.pipeline.rate_hz);
      bvh_thread = std::make_unique<outputs::FrameWriterThread>(*bvh);
      core.add_sink(bvh_thread.get());
    }
    if (!csv_path.empty()) {
      poses = std::make_unique<outputs::PosesCsvSink>(csv_path, 0);
      poses_thread = std::make_unique<outputs::FrameWriterThread>(*poses);
      core.add_sink(poses_thread.get());
    }
    const bool bar = !o.quiet && isatty(STDERR_FILENO);
    if (bar) {
      opt.progress = [](double f) {
        const int w = 40, n = static_cast<int>(f * w);
        std::fprintf(stderr, "\r[%.*s%*s] %5.1f%%", n, "########################################",
                     w - n, "", f * 100);
        if (f >= 1.0) std::fputc('\n', stderr);
      };
    }
    // The poses' time origin is the input's first sample.
    opt.on_first_sample = [&](int64_t t0) {
      if (poses) poses->set_t0(t0);
    };
    const int64_t wall0 = monotonic_ns();
    const ReplayResult r = daemon::run_replay(*src, core, opt);
    if (bvh) {
      bvh_thread->finish();
      bvh->close();
    }
    if (poses) {
      poses_thread->finish();
      poses->close();
    }
    const double wall_s = (monotonic_ns() - wall0) * 1e-9;
    const bool calibrated = engine.skeleton().calibration().valid;
    std::vector<std::string> outputs;
    if (!o.bvh.empty()) outputs.push_back(o.bvh);
    if (!csv_path.empty()) outputs.push_back(csv_path);
    print_run_summary("replay", input, outputs, static_cast<long long>(r.frames),
                      (r.t_last_ns - r.t_first_ns) * 1e-9,
                      {{"sensors", cfg.sensors.size()},
                       {"samples", r.samples},
                       {"wall_s", std::round(wall_s * 1000) / 1000},
                       {"calibrated", calibrated},
                       {"calibration", engine.last_calibration_message()}});
    if (!calibrated && !opt.calibrate_pose)
      std::fprintf(stderr,
                   "mocap replay: warning: %s holds no calibration and none was asked for: the "
                   "poses are the sensors' own orientations, not the body's (calibrate with "
                   "--calibrate npose@SECONDS at a moment the person stands in the pose)\n",
                   input.c_str());
    if (opt.calibrate_pose && !engine.skeleton().calibration().valid) {
      std::fprintf(stderr, "mocap replay: calibration at %.2f s failed: %s\n", opt.calibrate_at_s,
                   engine.last_calibration_message().empty()
                       ? "the input ended first"
                       : engine.last_calibration_message().c_str());
      return 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mocap replay: %s\n", e.what());
    return 1;
  }
}

}  // namespace

void add_replay(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<ReplayCommandOptions>();
  CLI::App* c =
      cli::add_command(app, "replay", "run a session or sample CSV through the pipeline offline");
  c->add_option("INPUT", o->input, "a session (.mocapses) or a CSV of samples")->required();
  CLI::Option* config = c->add_option(
      "--config", o->config,
      "rig configuration (TOML); default: the recorded one, or segment-named sensors");
  cli::add_deprecated_alias(*c, "--rig", o->config_alias, config);
  cli::add_multi(*c, "--set", o->sets, "override a configuration key (KEY=VALUE)");
  c->add_option("--bvh", o->bvh, "write the motion as BVH");
  c->add_option("--filter-threads", o->filter_threads,
                "threads for the sensors' filters besides the replay's own (default: cores - 1, "
                "at least 1; 0: all on one thread); the output is the same")
      ->check(CLI::Range(0, 64));
  CLI::Option* csv =
      c->add_option("--csv", o->csv, "write the poses as CSV: t,segment,w,x,y,z,px,py,pz");
  cli::add_deprecated_alias(*c, "--poses", o->csv_alias, csv);
  c->add_option("--calibrate", o->calibrate,
                "calibrate at a moment of the input: npose@SECONDS, tpose@SECONDS, or "
                "mounting@SECONDS (an N-pose, then the mounting motion)")
      ->check(CLI::Validator(
          [](std::string& v) {
            mocap::CalibrationPose pose;
            bool mounting = false;
            double at_s = 0;
            return parse_calibrate(v, pose, mounting, at_s)
                       ? std::string()
                       : "needs npose@SECONDS, tpose@SECONDS or mounting@SECONDS, got '" + v + "'";
          },
          "POSE@SECONDS"));
  c->add_option("--source", o->source,
                "session files: replay 'raw' device bytes or recorded 'samples' (default: "
                "samples if recorded)")
      ->check(CLI::IsMember({"raw", "samples"}));
  c->add_flag("--quiet", o->quiet, "no progress bar");
  c->callback([o, &exit_code] { exit_code = run_replay(*o); });
}

}  // namespace mocap::cmd
