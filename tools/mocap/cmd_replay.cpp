// mocap replay: runs a recorded session or a CSV of samples offline through the daemon's
// pipeline (filter -> calibration -> skeleton) and writes BVH and/or pose CSV.
//   mocap replay INPUT [--rig RIG.toml] [--set K=V] [--bvh OUT.bvh] [--poses OUT.csv]
//                [--calibrate npose@SECONDS|tpose@SECONDS] [--source raw|samples]
#include <unistd.h>

#include <cstdio>
#include <memory>
#include <optional>

#include "commands.hpp"
#include "mocap/core/cli_args.hpp"
#include "mocap/core/time.hpp"
#include "mocap/daemon/daemon.hpp"
#include "mocap/daemon/poses_csv.hpp"
#include "mocap/daemon/prefetch_source.hpp"
#include "mocap/daemon/replay.hpp"
#include "mocap/daemon/rig_engine.hpp"
#include "mocap/skeleton/body_model.hpp"
#include "mocap/skeleton/bvh.hpp"
#include "mocap/skeleton/dropout_bridge.hpp"

namespace mocap::cmd {

namespace {

using namespace mocap::daemon;

/// The replayed poses as BVH, a sensor's short dropouts bridged (as `mocap export` does).
class BvhSink final : public FrameSink {
 public:
  BvhSink(const std::string& path, const Config& cfg)
      : bridge_(BodyModel(cfg.body.model).dimensions()) {
    BvhWriterOptions o;
    o.frame_time_s = 1.0 / cfg.pipeline.rate_hz;
    writer_ = std::make_unique<BvhWriter>(path, BodyModel(cfg.body.model), o);
  }
  void publish(const PoseFrame& f) override {
    bridge_.push(f);
    drain();
  }
  void close() {
    bridge_.finish();
    drain();
    writer_->close();
  }
  int frames() const { return writer_->frames(); }

 private:
  void drain() {
    while (bridge_.next(out_))
      writer_->write_frame(out_);
  }
  DropoutBridge bridge_;
  PoseFrame out_;
  std::unique_ptr<BvhWriter> writer_;
};

bool parse_calibrate(const std::string& s, mocap::CalibrationPose& pose, double& at_s) {
  const auto at = s.find('@');
  if (at == std::string::npos) return false;
  const std::string p = s.substr(0, at);
  if (p == "npose")
    pose = mocap::CalibrationPose::npose;
  else if (p == "tpose")
    pose = mocap::CalibrationPose::tpose;
  else
    return false;
  char* end = nullptr;
  at_s = std::strtod(s.c_str() + at + 1, &end);
  return end && *end == '\0' && at + 1 < s.size() && at_s >= 0;
}

}  // namespace

int run_replay(int argc, char** argv) {
  CliArgs args;
  args.flag("help", "show this help")
      .option("rig",
              "rig configuration (TOML); default: the recorded one, or segment-named sensors")
      .multi("set", "override a configuration key (KEY=VALUE)")
      .option("bvh", "write the motion as BVH")
      .option("poses", "write poses as CSV: t,segment,w,x,y,z,px,py,pz")
      .option("calibrate", "calibrate at a moment of the input: npose@SECONDS or tpose@SECONDS")
      .option("source", "session files: replay 'raw' device bytes or recorded 'samples'")
      .flag("quiet", "no progress bar");
  if (!args.parse(argc, argv) || args.has("help") || args.positional().size() != 1) {
    if (!args.error().empty()) std::fprintf(stderr, "mocap replay: %s\n", args.error().c_str());
    std::fprintf(args.has("help") ? stdout : stderr,
                 "usage: mocap replay INPUT(.mocapses session | .csv samples) [options]\n%s",
                 args.help().c_str());
    return args.has("help") ? 0 : 2;
  }
  const std::string input = args.positional()[0];
  std::optional<Config> rig;
  const auto sets = args.get_all("set");
  if (auto r = args.get("rig")) {
    ConfigErrors errs;
    rig = load_config(*r, sets, errs, &default_validators());
    if (!rig) {
      std::fprintf(stderr, "%s", errs.to_string().c_str());
      return 1;
    }
  }
  ReplayOptions opt;
  if (auto c = args.get("calibrate")) {
    mocap::CalibrationPose pose;
    if (!parse_calibrate(*c, pose, opt.calibrate_at_s)) {
      std::fprintf(stderr,
                   "mocap replay: --calibrate needs npose@SECONDS or tpose@SECONDS, got '%s'\n",
                   c->c_str());
      return 2;
    }
    opt.calibrate_pose = pose;
  }
  SessionSource which = SessionSource::automatic;
  if (auto s = args.get("source")) {
    if (*s == "raw")
      which = SessionSource::raw;
    else if (*s == "samples")
      which = SessionSource::samples;
    else {
      std::fprintf(stderr, "mocap replay: --source is raw or samples\n");
      return 2;
    }
  }
  try {
    std::unique_ptr<SampleSource> src;
    if (args.has("source"))
      src = open_session_source(input, rig ? &*rig : nullptr, which);
    else
      src = open_sample_source(input, rig ? &*rig : nullptr);
    // Read and decode the file on the other core while this one filters and solves.
    src = std::make_unique<PrefetchSource>(std::move(src));
    Config cfg = src->config();
    if (!rig) {
      // --set without --rig: applied to the input's own configuration (recorded, or the
      // segment-named sensors of a CSV).
      ConfigErrors errs;
      std::optional<Config> with_sets = with_overrides(cfg, sets, input + " (configuration)", errs);
      if (!with_sets) {
        std::fprintf(stderr, "%s", errs.to_string().c_str());
        return 1;
      }
      cfg = *with_sets;
    }
    // Calibrate immediately at the chosen moment (the file is the countdown).
    cfg.calibration.countdown_s = 0;
    // A replay uses the session's own calibration and never writes the live calibration file.
    cfg.calibration.file.clear();
    RigEngine engine(cfg);
    if (const std::string ct = src->calibration_text(); !ct.empty() && !opt.calibrate_pose)
      engine.tracker().set_calibration(parse_calibration(ct, input + " (calibration)"));
    PipelineCore core(cfg.pipeline, cfg.calibration, sensor_infos(cfg), engine);
    core.set_frame_flag(kFrameReplay, true);
    std::unique_ptr<BvhSink> bvh;
    std::unique_ptr<PosesCsvSink> poses;
    if (auto p = args.get("bvh")) {
      bvh = std::make_unique<BvhSink>(*p, cfg);
      core.add_sink(bvh.get());
    }
    if (auto p = args.get("poses")) {
      poses = std::make_unique<PosesCsvSink>(*p, 0);
      core.add_sink(poses.get());
    }
    const bool bar = !args.has("quiet") && isatty(STDERR_FILENO);
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
    if (bvh) bvh->close();
    if (poses) poses->close();
    const double wall_s = (monotonic_ns() - wall0) * 1e-9;
    std::printf(
        "{\"input\":\"%s\",\"sensors\":%zu,\"samples\":%llu,\"frames\":%llu,"
        "\"duration_s\":%.3f,\"wall_s\":%.3f,\"calibration\":\"%s\"}\n",
        input.c_str(), cfg.sensors.size(), static_cast<unsigned long long>(r.samples),
        static_cast<unsigned long long>(r.frames), (r.t_last_ns - r.t_first_ns) * 1e-9, wall_s,
        engine.last_calibration_message().c_str());
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

}  // namespace mocap::cmd
