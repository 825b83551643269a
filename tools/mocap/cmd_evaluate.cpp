// mocap evaluate: scores an attitude algorithm on every BROAD trial of a directory with the
// benchmark's metric and prints per-trial and mean RMS errors (total, heading, inclination).
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "mocap/core/cli.hpp"
#include "mocap/eval/broad_metric.hpp"
#include "mocap/eval/run_trial.hpp"
#include "mocap/filter/filter_param_names.hpp"

namespace mocap::cmd {
namespace {

const VqfRef* vqf_for(const std::string& name) {
  return vqf_reference(name);
}

/// mocap evaluate's command line (declared in add_evaluate).
struct EvaluateOptions {
  std::string dir, mode = "9d", algorithm = "default";
  std::vector<std::string> sets;
  double gyr_range_dps = 0;
  bool quiet = false;
};

int run_evaluate(const EvaluateOptions& o) {
  const auto mode = parse_filter_mode(o.mode);
  const auto alg = parse_filter_algorithm(o.algorithm);
  FilterParams params;
  for (const auto& kv : o.sets) {
    std::string err;
    if (!set_filter_param(params, kv, err)) {
      std::fprintf(stderr, "mocap evaluate: --set %s: %s\n", kv.c_str(), err.c_str());
      return 2;
    }
  }
  const std::string dir = o.dir.empty() ? default_broad_dir() : o.dir;
  const auto files = list_broad_trials(dir);
  if (files.empty()) {
    std::fprintf(stderr, "mocap evaluate: no *.csv or *.csv.gz trials in '%s'\n", dir.c_str());
    return 1;
  }
  const bool quiet = o.quiet;
  const bool nine = *mode == FilterMode::k9d;
  if (!quiet)
    std::printf("%-44s %7s %7s %7s   %s\n", "trial", "total", "heading", "incl",
                nine ? "VQF total/heading (diff)" : "VQF 6D incl (diff)");
  double sum_t = 0, sum_h = 0, sum_i = 0, worst = -1e9;
  std::string worst_name;
  BroadTrial trial;
  std::vector<Eigen::Quaterniond> est;
  int n = 0;
  for (const auto& f : files) {
    std::string err;
    if (!read_broad_csv(f, trial, err)) {
      std::fprintf(stderr, "mocap evaluate: %s\n", err.c_str());
      return 1;
    }
    if (!trial.has_ref) {
      std::fprintf(stderr, "mocap evaluate: %s: no ref_w..ref_z columns to score against\n",
                   f.c_str());
      return 1;
    }
    size_t clipped = 0;
    if (o.gyr_range_dps > 0) clipped = clip_gyro(trial, o.gyr_range_dps);
    run_trial(trial, *alg, *mode, params, est);
    const AttitudeErrors e = score_trial(trial, est);
    sum_t += e.total_deg;
    sum_h += e.heading_deg;
    sum_i += e.inclination_deg;
    ++n;
    const VqfRef* v = vqf_for(trial.name);
    double diff = 0;
    if (v) diff = nine ? e.total_deg - v->total : e.inclination_deg - v->incl6;
    if (v && diff > worst) {
      worst = diff;
      worst_name = trial.name;
    }
    if (quiet) continue;
    std::printf("%-44s %7.3f %7.3f %7.3f", trial.name.c_str(), e.total_deg, e.heading_deg,
                e.inclination_deg);
    if (v && nine)
      std::printf("   %5.2f / %5.2f (%+.2f / %+.2f)", v->total, v->heading, diff,
                  e.heading_deg - v->heading);
    else if (v)
      std::printf("   %5.2f (%+.2f)", v->incl6, diff);
    if (o.gyr_range_dps > 0) std::printf("   %zu clipped", clipped);
    std::printf("\n");
  }
  std::printf("%-44s %7.3f %7.3f %7.3f   worst vs VQF: %+.2f (%s)\n",
              ("MEAN of " + std::to_string(n) + " (" + filter_algorithm_name(*alg) + ", " +
               (nine ? "9d" : "6d") + ")")
                  .c_str(),
              sum_t / n, sum_h / n, sum_i / n, worst, worst_name.c_str());
  return 0;
}

}  // namespace

void add_evaluate(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<EvaluateOptions>();
  CLI::App* c = cli::add_command(app, "evaluate", "score attitude filters on the BROAD trials");
  c->add_option("DIR", o->dir,
                "directory of *.csv(.gz) trials (default: the shared BROAD trials, " +
                    default_broad_dir() + ")");
  c->add_option("--mode", o->mode, "9d or 6d")
      ->check(CLI::IsMember({"9d", "6d"}, CLI::ignore_case));
  c->add_option("--algorithm", o->algorithm, "default (ours), madgwick or mahony")
      ->check(CLI::IsMember({"default", "ours", "madgwick", "mahony"}));
  cli::add_multi(*c, "--set", o->sets,
                 "override a filter parameter: --set tau_mag_s=12 (ours only)");
  c->add_option("--gyr-range-dps", o->gyr_range_dps,
                "read the gyro as a sensor of this full scale would (clipped and flagged): "
                "how the filter recovers from rotation it could not measure")
      ->check(CLI::PositiveNumber);
  c->add_flag("--quiet", o->quiet, "print only the mean line");
  c->callback([o, &exit_code] { exit_code = run_evaluate(*o); });
}

}  // namespace mocap::cmd
