// mocap perform: runs the virtual performer offline and writes its files — the sensors'
// samples as the interchange IMU CSV (what `mocap replay` and `mocap filter` read), the ground
// truth as a pose CSV, and the truth as a BVH file (which `demo.motion` and `mocap bench accuracy
// --motion` take back as motion input).
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "mocap/core/cli.hpp"
#include "mocap/sim/csv_writers.hpp"
#include "mocap/sim/performer.hpp"
#include "mocap/sim/sensor_model.hpp"
#include "mocap/skeleton/bvh.hpp"

namespace mocap::cmd {

namespace {

/// mocap perform's command line (declared in add_perform).
struct PerformOptions {
  sim::PerformerParams pp;
  long seed = 1;
  bool ideal = false;
  double duration_s = -1, bvh_rate_hz = 60;
  std::string disturbance = "none", samples, truth, bvh;
};

int run_perform(PerformOptions& o) {
  sim::PerformerParams& pp = o.pp;
  const long seed = o.seed;
  const double duration_s = o.duration_s, bvh_rate_hz = o.bvh_rate_hz;
  pp.seed = static_cast<uint64_t>(seed);
  if (o.ideal) pp.sensor = sim::SensorModelParams::ideal();
  try {
    pp.field.dipoles = sim::disturbance_preset(o.disturbance, pp.height_m);
    sim::Performer perf(pp);
    const double end_s = duration_s >= 0 ? duration_s : perf.track().period_s();
    std::unique_ptr<sim::ImuCsvWriter> samples_csv;
    std::unique_ptr<sim::TruthCsvWriter> truth_csv;
    std::unique_ptr<BvhWriter> bvh;
    if (!o.samples.empty()) {
      std::vector<std::string> names;
      for (int i = 0; i < sim::Performer::kSensorCount; ++i)
        names.emplace_back(sim::Performer::sensor_name(i));
      samples_csv = std::make_unique<sim::ImuCsvWriter>(o.samples, names, pp.t0_ns);
    }
    if (!o.truth.empty()) truth_csv = std::make_unique<sim::TruthCsvWriter>(o.truth);
    if (!o.bvh.empty()) {
      BvhWriterOptions bo;
      bo.frame_time_s = 1.0 / bvh_rate_hz;
      bvh = std::make_unique<BvhWriter>(o.bvh, BodyModel(perf.dims()), bo);
    }
    // Truth and BVH frames on their own grids; samples as the performer emits them.
    const double truth_period_s = 1.0 / pp.rate_hz, bvh_period_s = 1.0 / bvh_rate_hz;
    std::vector<ImuSample> out;
    out.reserve(4096);
    sim::TruthFrame t;
    long n_samples = 0, n_truth = 0;
    for (long k = 0; k * bvh_period_s <= end_s + 1e-9 && bvh; ++k) {
      perf.truth_at(k * bvh_period_s, t);
      bvh->write_frame(sim::to_pose_frame(t));
    }
    for (long k = 0; k * truth_period_s <= end_s + 1e-9; ++k) {
      const double t_s = k * truth_period_s;
      if (samples_csv) {
        out.clear();
        perf.step_to(pp.t0_ns + static_cast<int64_t>(std::llround(t_s * 1e9)), out);
        for (const ImuSample& s : out)
          samples_csv->write(s);
        n_samples += static_cast<long>(out.size());
      }
      if (truth_csv) {
        perf.truth_at(t_s, t);
        truth_csv->write(t);
        ++n_truth;
      }
    }
    if (samples_csv) samples_csv->close();
    if (truth_csv) truth_csv->close();
    if (bvh) bvh->close();
    std::fprintf(stderr,
                 "mocap perform: %s, %.2f s: %ld samples, %ld truth frames%s%s (calibration "
                 "stand %.1f..%.1f s)\n",
                 pp.motion.c_str(), end_s, n_samples, n_truth, bvh ? ", BVH " : "",
                 bvh ? o.bvh.c_str() : "", perf.calibration_window_s().first,
                 perf.calibration_window_s().second);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mocap perform: %s\n", e.what());
    return 1;
  }
  return 0;
}

}  // namespace

void add_perform(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<PerformOptions>();
  o->pp.motion = "sequence";
  o->pp.loop = false;
  CLI::App* c = cli::add_command(
      app, "perform", "run the virtual performer: its samples, ground truth and BVH to files");
  c->footer("At least one output. The motion plays once (default: its whole length).");
  c->add_option("--motion", o->pp.motion,
                "a motion name (sim::motion_names(), optionally calibrate+) or a BVH file");
  c->add_option("--seed", o->seed, "random seed of the sensor errors and mountings")
      ->check(CLI::NonNegativeNumber);
  c->add_option("--rate", o->pp.rate_hz, "sensor sample rate, Hz")->check(CLI::PositiveNumber);
  CLI::Option* height = c->add_option("--body-height", o->pp.height_m,
                                      "performer height, m (a BVH file brings its own bones)")
                            ->check(CLI::Range(0.5, 2.6));
  cli::add_deprecated_alias(*c, "--height", o->pp.height_m, height);
  c->add_option("--disturbance", o->disturbance, "magnetic disturbance: none|magnet|desk|both");
  c->add_flag("--ideal", o->ideal, "ideal sensors (no noise, bias, scale error, misalignment)");
  c->add_option("--duration", o->duration_s, "seconds to perform (default: the motion's length)")
      ->default_str("");
  CLI::Option* samples = c->add_option("--samples", o->samples,
                                       "write the sensors' samples here (interchange IMU CSV)");
  CLI::Option* truth = c->add_option(
      "--truth", o->truth, "write the ground-truth poses here (t,segment,w,x,y,z,px,py,pz)");
  CLI::Option* bvh = c->add_option("--bvh", o->bvh, "write the ground truth here as BVH");
  c->add_option("--bvh-rate", o->bvh_rate_hz, "frame rate of the --bvh file, Hz")
      ->check(CLI::Range(1.0, 1000.0))
      ->needs(bvh);
  c->callback([o, &exit_code, samples, truth, bvh] {
    if (!samples->count() && !truth->count() && !bvh->count()) {
      std::fprintf(stderr, "mocap perform: nothing to write (--samples, --truth or --bvh)\n");
      exit_code = 2;
      return;
    }
    exit_code = run_perform(*o);
  });
}

}  // namespace mocap::cmd
