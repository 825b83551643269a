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
#include "mocap/core/cli_args.hpp"
#include "mocap/sim/csv_writers.hpp"
#include "mocap/sim/performer.hpp"
#include "mocap/sim/sensor_model.hpp"
#include "mocap/skeleton/bvh.hpp"

namespace mocap::cmd {

namespace {

constexpr const char* kPerformUsage =
    "usage: mocap perform [--motion NAME|FILE.bvh] [--seed N] [--rate HZ] [--height M]\n"
    "                     [--disturbance none|magnet|desk|both] [--ideal] [--duration S]\n"
    "                     [--samples OUT.csv] [--truth OUT.csv] [--bvh OUT.bvh [--bvh-rate HZ]]\n"
    "  At least one output. The motion plays once (default: its whole length).\n";

PoseFrame to_pose_frame(const sim::TruthFrame& t) {
  PoseFrame f;
  for (int s = 0; s < kSegmentCount; ++s) {
    const auto& q = t.q_earth_segment[s];
    const auto& j = t.q_parent_segment[s];
    const auto& p = t.p_earth_segment_m[s];
    f.q_earth_segment[s] = {float(q.w()), float(q.x()), float(q.y()), float(q.z())};
    f.q_parent_segment[s] = {float(j.w()), float(j.x()), float(j.y()), float(j.z())};
    f.p_earth_segment_m[s] = {float(p.x()), float(p.y()), float(p.z())};
  }
  return f;
}

}  // namespace

int run_perform(int argc, char** argv) {
  CliArgs args;
  args.option("motion", "a motion name (sim::motion_names(), optionally calibrate+) or a BVH file")
      .option("seed", "random seed of the sensor errors and mountings (default 1)")
      .option("rate", "sensor sample rate, Hz (default 100)")
      .option("height", "performer height, m (default 1.75; a BVH file brings its own bones)")
      .option("disturbance", "magnetic disturbance: none|magnet|desk|both (default none)")
      .flag("ideal", "ideal sensors (no noise, bias, scale error, misalignment)")
      .option("duration", "seconds to perform (default: the motion's length)")
      .option("samples", "write the sensors' samples here (interchange IMU CSV)")
      .option("truth", "write the ground-truth poses here (t,segment,w,x,y,z,px,py,pz)")
      .option("bvh", "write the ground truth here as BVH")
      .option("bvh-rate", "BVH frame rate, Hz (default 60)")
      .flag("help", "show this help");
  if (!args.parse(argc, argv)) {
    std::fprintf(stderr, "mocap perform: %s\n%s", args.error().c_str(), kPerformUsage);
    return 2;
  }
  if (args.has("help")) {
    std::printf("%s%s", kPerformUsage, args.help().c_str());
    return 0;
  }
  sim::PerformerParams pp;
  pp.motion = args.get_or("motion", "sequence");
  pp.loop = false;
  long seed = 1;
  double duration_s = -1, bvh_rate_hz = 60;
  if ((args.has("seed") && (!args.get_int("seed", seed) || seed < 0)) ||
      (args.has("rate") && !args.get_double("rate", pp.rate_hz)) ||
      (args.has("height") && !args.get_double("height", pp.height_m)) ||
      (args.has("duration") && !args.get_double("duration", duration_s)) ||
      (args.has("bvh-rate") && !args.get_double("bvh-rate", bvh_rate_hz))) {
    std::fprintf(stderr, "mocap perform: %s\n",
                 args.error().empty() ? "--seed must be >= 0" : args.error().c_str());
    return 2;
  }
  if (!(bvh_rate_hz >= 1 && bvh_rate_hz <= 1000)) {
    std::fprintf(stderr, "mocap perform: --bvh-rate must be in [1, 1000] Hz\n");
    return 2;
  }
  if (!args.has("samples") && !args.has("truth") && !args.has("bvh")) {
    std::fprintf(stderr, "mocap perform: nothing to write (--samples, --truth or --bvh)\n%s",
                 kPerformUsage);
    return 2;
  }
  pp.seed = static_cast<uint64_t>(seed);
  if (args.has("ideal")) pp.sensor = sim::SensorModelParams::ideal();
  try {
    pp.field.dipoles = sim::disturbance_preset(args.get_or("disturbance", "none"), pp.height_m);
    sim::Performer perf(pp);
    const double end_s = duration_s >= 0 ? duration_s : perf.track().period_s();
    std::unique_ptr<sim::ImuCsvWriter> samples_csv;
    std::unique_ptr<sim::TruthCsvWriter> truth_csv;
    std::unique_ptr<BvhWriter> bvh;
    if (auto p = args.get("samples")) {
      std::vector<std::string> names;
      for (int i = 0; i < sim::Performer::kSensorCount; ++i)
        names.emplace_back(sim::Performer::sensor_name(i));
      samples_csv = std::make_unique<sim::ImuCsvWriter>(*p, names, pp.t0_ns);
    }
    if (auto p = args.get("truth")) truth_csv = std::make_unique<sim::TruthCsvWriter>(*p);
    if (auto p = args.get("bvh")) {
      BvhWriterOptions o;
      o.frame_time_s = 1.0 / bvh_rate_hz;
      bvh = std::make_unique<BvhWriter>(*p, BodyModel(perf.dims()), o);
    }
    // Truth and BVH frames on their own grids; samples as the performer emits them.
    const double truth_period_s = 1.0 / pp.rate_hz, bvh_period_s = 1.0 / bvh_rate_hz;
    std::vector<ImuSample> out;
    out.reserve(4096);
    sim::TruthFrame t;
    long n_samples = 0, n_truth = 0;
    for (long k = 0; k * bvh_period_s <= end_s + 1e-9 && bvh; ++k) {
      perf.truth_at(k * bvh_period_s, t);
      bvh->write_frame(to_pose_frame(t));
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
                 bvh ? args.get("bvh")->c_str() : "", perf.calibration_window_s().first,
                 perf.calibration_window_s().second);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mocap perform: %s\n", e.what());
    return 1;
  }
  return 0;
}

}  // namespace mocap::cmd
