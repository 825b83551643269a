// mocap filter: runs an attitude filter over a BROAD-layout sample CSV (plain or .gz) and
// writes one "w,x,y,z" line (sensor -> ENU) per input sample.
#include <cstdio>
#include <string>
#include <vector>

#include "commands.hpp"
#include "mocap/core/cli_args.hpp"
#include "mocap/eval/run_trial.hpp"
#include "mocap/filter/filter_param_names.hpp"

namespace mocap::cmd {

int run_filter(int argc, char** argv) {
  CliArgs args;
  args.option("mode", "9d (default; gyro+acc+mag) or 6d (gyro+acc)")
      .option("algorithm", "default (ours), madgwick or mahony")
      .multi("set", "override a filter parameter: --set tau_mag_s=12 (ours only)")
      .flag("help", "show this help");
  const bool ok = args.parse(argc, argv);
  if (!ok || args.positional().size() != 2 || args.has("help")) {
    FILE* out = args.has("help") ? stdout : stderr;
    if (!ok) std::fprintf(out, "mocap filter: %s\n", args.error().c_str());
    std::fprintf(out,
                 "usage: mocap filter INPUT OUTPUT [--mode 9d|6d] [--algorithm NAME]\n"
                 "INPUT: CSV (or .csv.gz) with a header t,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z"
                 "[,mag_x,mag_y,mag_z,...];\n"
                 "OUTPUT: one line w,x,y,z (sensor to ENU) per input sample.\n%s",
                 args.help().c_str());
    return args.has("help") ? 0 : 2;
  }
  const auto mode = parse_filter_mode(args.get_or("mode", "9d"));
  if (!mode) {
    std::fprintf(stderr, "mocap filter: --mode must be 9d or 6d\n");
    return 2;
  }
  const auto alg = parse_filter_algorithm(args.get_or("algorithm", "default"));
  if (!alg) {
    std::fprintf(stderr, "mocap filter: --algorithm must be default, madgwick or mahony\n");
    return 2;
  }
  FilterParams params;
  for (const auto& kv : args.get_all("set")) {
    std::string err;
    if (!set_filter_param(params, kv, err)) {
      std::fprintf(stderr, "mocap filter: --set %s: %s\n", kv.c_str(), err.c_str());
      return 2;
    }
  }
  const std::string& in = args.positional()[0];
  const std::string& out_path = args.positional()[1];
  BroadTrial trial;
  std::string err;
  if (!read_broad_csv(in, trial, err)) {
    std::fprintf(stderr, "mocap filter: %s\n", err.c_str());
    return 1;
  }
  if (*mode == FilterMode::k9d && !trial.has_mag) {
    std::fprintf(stderr, "mocap filter: %s: --mode 9d needs mag_x,mag_y,mag_z columns\n",
                 in.c_str());
    return 1;
  }
  std::vector<Eigen::Quaterniond> q;
  run_trial(trial, *alg, *mode, params, q);
  FILE* f = std::fopen(out_path.c_str(), "w");
  if (!f) {
    std::fprintf(stderr, "mocap filter: %s: cannot open for writing\n", out_path.c_str());
    return 1;
  }
  for (const auto& e : q)
    std::fprintf(f, "%.9f,%.9f,%.9f,%.9f\n", e.w(), e.x(), e.y(), e.z());
  if (std::fclose(f) != 0) {
    std::fprintf(stderr, "mocap filter: %s: write failed\n", out_path.c_str());
    return 1;
  }
  std::fprintf(stderr, "mocap filter: %zu samples, %.3f Hz, %s %s -> %s\n", trial.size(),
               trial.rate_hz, filter_algorithm_name(*alg), *mode == FilterMode::k9d ? "9d" : "6d",
               out_path.c_str());
  return 0;
}

}  // namespace mocap::cmd
