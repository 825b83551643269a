// mocap filter: runs an attitude filter over a BROAD-layout sample CSV (plain or .gz) and
// writes one "w,x,y,z" line (sensor -> ENU) per input sample.
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "mocap/core/cli.hpp"
#include "mocap/eval/run_trial.hpp"
#include "mocap/filter/filter_param_names.hpp"

namespace mocap::cmd {

namespace {

/// mocap filter's command line (declared in add_filter).
struct FilterOptions {
  std::string input, output, mode = "9d", algorithm = "default";
  std::vector<std::string> sets;
  double gyr_range_dps = 0;
};

int run_filter(const FilterOptions& o) {
  const auto mode = parse_filter_mode(o.mode);
  if (!mode) {
    std::fprintf(stderr, "mocap filter: --mode must be 9d or 6d\n");
    return 2;
  }
  const auto alg = parse_filter_algorithm(o.algorithm);
  if (!alg) {
    std::fprintf(stderr, "mocap filter: --algorithm must be default, madgwick or mahony\n");
    return 2;
  }
  FilterParams params;
  for (const auto& kv : o.sets) {
    std::string err;
    if (!set_filter_param(params, kv, err)) {
      std::fprintf(stderr, "mocap filter: --set %s: %s\n", kv.c_str(), err.c_str());
      return 2;
    }
  }
  const std::string& in = o.input;
  const std::string& out_path = o.output;
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
  if (o.gyr_range_dps > 0) clip_gyro(trial, o.gyr_range_dps);
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

}  // namespace

void add_filter(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<FilterOptions>();
  CLI::App* c = cli::add_command(app, "filter", "run an attitude filter over a CSV of IMU samples");
  c->footer(
      "INPUT: CSV (or .csv.gz) with a header t,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z"
      "[,mag_x,mag_y,mag_z,...];\nOUTPUT: one line w,x,y,z (sensor to ENU) per input sample.");
  c->add_option("INPUT", o->input, "samples CSV (or .csv.gz)")->required();
  c->add_option("OUTPUT", o->output, "quaternions CSV to write")->required();
  c->add_option("--mode", o->mode, "9d (gyro+acc+mag) or 6d (gyro+acc)")
      ->check(CLI::IsMember({"9d", "6d"}, CLI::ignore_case));
  c->add_option("--algorithm", o->algorithm, "default (ours), madgwick or mahony")
      ->check(CLI::IsMember({"default", "ours", "madgwick", "mahony"}));
  cli::add_multi(*c, "--set", o->sets,
                 "override a filter parameter: --set tau_mag_s=12 (ours only)");
  c->add_option("--gyr-range-dps", o->gyr_range_dps,
                "read the gyro as a sensor of this full scale would (clipped and flagged)")
      ->check(CLI::PositiveNumber);
  c->callback([o, &exit_code] { exit_code = run_filter(*o); });
}

}  // namespace mocap::cmd
