// mocap bench filter: every attitude algorithm over the same real samples in one process;
// prints JSON with ns per update (6D and 9D; the measuring thread's CPU time, best of the
// rounds) and the ratio of ours to Madgwick.
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "bench.hpp"
#include "mocap/core/cli.hpp"
#include "mocap/eval/madgwick.hpp"
#include "mocap/eval/mahony.hpp"
#include "mocap/eval/run_trial.hpp"
#include "mocap/filter/attitude_filter.hpp"
#include "mocap/filter/filter_param_names.hpp"

namespace mocap::bench {
namespace {

// The orientation as a consumer reads it: AttitudeFilter through its one read API, output().
double q_w(const AttitudeFilter& f) {
  return f.output().q_earth_sensor.w();
}
template <class F>
double q_w(const F& f) {
  return f.q_earth_sensor().w();
}

// This thread's CPU time, ns: a round's time without the time other processes held the core
// (a round of ours takes ~20 ms, longer than a time slice on a busy machine, Madgwick's ~5 ms:
// wall time would charge the preemptions mostly to the longer rounds).
int64_t thread_cpu_ns() {
  timespec ts{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

// Best-of-rounds ns per update of a fresh filter over all samples (min rejects noise from
// other processes on the shared machine). The sink keeps the output live.
template <class Make>
double ns_per_update(Make make, const std::vector<ImuSample>& samples, int rounds, double& sink) {
  double best = 1e300;
  for (int r = 0; r < rounds; ++r) {
    auto f = make();
    const int64_t t0 = thread_cpu_ns();
    for (const auto& s : samples) {
      f.update(s);
      sink += q_w(f);
    }
    const int64_t t1 = thread_cpu_ns();
    best = std::min(best, static_cast<double>(t1 - t0) / static_cast<double>(samples.size()));
  }
  return best;
}

int run_filter(std::string path, int rounds) {
  if (path.empty()) {
    const auto files = list_broad_trials(default_broad_dir());
    if (files.empty()) {
      std::fprintf(stderr, "mocap bench filter: no trials in %s\n", default_broad_dir().c_str());
      return 1;
    }
    path = files.front();
  }
  BroadTrial trial;
  std::string err;
  if (!read_broad_csv(path, trial, err)) {
    std::fprintf(stderr, "mocap bench filter: %s\n", err.c_str());
    return 1;
  }
  double sink = 0;
  struct Row {
    const char* name;
    double ns6, ns9;
  } rows[3] = {{"default", 1e300, 1e300}, {"madgwick", 1e300, 1e300}, {"mahony", 1e300, 1e300}};
  std::vector<ImuSample> s6(trial.size()), s9(trial.size());
  for (size_t i = 0; i < trial.size(); ++i) {
    s6[i] = trial_sample(trial, i, FilterMode::k6d);
    s9[i] = trial_sample(trial, i, FilterMode::k9d);
  }
  // Rounds interleave the algorithms so that load from other processes hits all alike; the
  // minimum over rounds is reported.
  for (int r = 0; r < rounds; ++r) {
    for (int m = 0; m < 2; ++m) {
      const bool mag = m == 1;
      const auto& samples = mag ? s9 : s6;
      const double t[3] = {ns_per_update([] { return AttitudeFilter(); }, samples, 1, sink),
                           ns_per_update(
                               [mag] {
                                 MadgwickParams p;
                                 p.use_mag = mag;
                                 return MadgwickFilter(p);
                               },
                               samples, 1, sink),
                           ns_per_update(
                               [mag] {
                                 MahonyParams p;
                                 p.use_mag = mag;
                                 return MahonyFilter(p);
                               },
                               samples, 1, sink)};
      for (int a = 0; a < 3; ++a) {
        double& dst = mag ? rows[a].ns9 : rows[a].ns6;
        dst = std::min(dst, t[a]);
      }
    }
  }
  std::printf("{\n  \"trial\": \"%s\",\n  \"samples\": %zu,\n  \"rounds\": %d,\n",
              trial.name.c_str(), trial.size(), rounds);
  std::printf("  \"ns_per_update\": {\n");
  for (int i = 0; i < 3; ++i)
    std::printf("    \"%s\": {\"6d\": %.1f, \"9d\": %.1f}%s\n", rows[i].name, rows[i].ns6,
                rows[i].ns9, i < 2 ? "," : "");
  std::printf("  },\n  \"ratio_default_to_madgwick\": {\"6d\": %.2f, \"9d\": %.2f},\n",
              rows[0].ns6 / rows[1].ns6, rows[0].ns9 / rows[1].ns9);
  std::printf("  \"checksum\": %.6f\n}\n", sink);
  return 0;
}

}  // namespace

void add_filter(CLI::App& bench, int& exit_code) {
  struct Options {
    std::string trial;
    int rounds = 9;
  };
  auto o = std::make_shared<Options>();
  CLI::App* c = cli::add_command(bench, "filter",
                                 "ns per update of each attitude algorithm, ratio to Madgwick");
  c->add_option("TRIAL", o->trial, "a BROAD trial CSV(.gz) (default: the first shared trial)");
  c->add_option("--rounds", o->rounds, "timed rounds (the best counts)")
      ->check(CLI::Range(1, 1000000));
  c->callback([o, &exit_code] { exit_code = run_filter(o->trial, o->rounds); });
}

}  // namespace mocap::bench
