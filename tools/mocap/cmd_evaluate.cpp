// mocap evaluate: scores an attitude algorithm on every BROAD trial of a directory with the
// benchmark's metric and prints per-trial and mean RMS errors (total, heading, inclination).
#include <cstdio>
#include <string>
#include <vector>

#include "commands.hpp"
#include "mocap/core/cli_args.hpp"
#include "mocap/eval/broad_metric.hpp"
#include "mocap/eval/run_trial.hpp"
#include "mocap/filter/filter_param_names.hpp"

namespace mocap::cmd {
namespace {

const VqfRef* vqf_for(const std::string& name) {
  return vqf_reference(name);
}

}  // namespace

int run_evaluate(int argc, char** argv) {
  CliArgs args;
  args.option("mode", "9d (default) or 6d")
      .option("algorithm", "default (ours), madgwick or mahony")
      .multi("set", "override a filter parameter: --set tau_mag_s=12 (ours only)")
      .flag("quiet", "print only the mean line")
      .flag("help", "show this help");
  if (!args.parse(argc, argv) || args.positional().size() > 1 || args.has("help")) {
    std::fprintf(args.has("help") ? stdout : stderr,
                 "%susage: mocap evaluate [DIR] [--mode 9d|6d] [--algorithm NAME]\n"
                 "Scores all *.csv(.gz) trials in DIR (default: the shared BROAD trials).\n%s",
                 args.error().empty() ? "" : ("mocap evaluate: " + args.error() + "\n").c_str(),
                 args.help().c_str());
    return args.has("help") ? 0 : 2;
  }
  const auto mode = parse_filter_mode(args.get_or("mode", "9d"));
  const auto alg = parse_filter_algorithm(args.get_or("algorithm", "default"));
  if (!mode || !alg) {
    std::fprintf(stderr,
                 "mocap evaluate: bad --mode (9d|6d) or --algorithm "
                 "(default|madgwick|mahony)\n");
    return 2;
  }
  FilterParams params;
  for (const auto& kv : args.get_all("set")) {
    std::string err;
    if (!set_filter_param(params, kv, err)) {
      std::fprintf(stderr, "mocap evaluate: --set %s: %s\n", kv.c_str(), err.c_str());
      return 2;
    }
  }
  const std::string dir =
      args.positional().empty() ? default_broad_dir() : args.positional().front();
  const auto files = list_broad_trials(dir);
  if (files.empty()) {
    std::fprintf(stderr, "mocap evaluate: no *.csv or *.csv.gz trials in '%s'\n", dir.c_str());
    return 1;
  }
  const bool quiet = args.has("quiet");
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
    std::printf("\n");
  }
  std::printf("%-44s %7.3f %7.3f %7.3f   worst vs VQF: %+.2f (%s)\n",
              ("MEAN of " + std::to_string(n) + " (" + filter_algorithm_name(*alg) + ", " +
               (nine ? "9d" : "6d") + ")")
                  .c_str(),
              sum_t / n, sum_h / n, sum_i / n, worst, worst_name.c_str());
  return 0;
}

}  // namespace mocap::cmd
