// mocap stills: the attitude filter's inclination at each sensor's still moments in a sample
// CSV (plain or .gz, `mocap replay`'s layout, any number of sensors): a check on real
// recordings without optical truth (eval/still_check.hpp). Prints per sensor the RMS error at
// the onset of its stands (>= 1 s) and stances (short still moments: a foot flat on the floor)
// and the mean over sensors.
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "mocap/core/cli.hpp"
#include "mocap/daemon/sample_csv.hpp"
#include "mocap/daemon/text_lines.hpp"
#include "mocap/eval/still_check.hpp"
#include "mocap/filter/filter_param_names.hpp"

namespace mocap::cmd {
namespace {

/// mocap stills' command line (declared in add_stills).
struct StillsOptions {
  std::string input, mode = "6d";
  std::vector<std::string> sets;
  StillCheckOptions check;
  bool verbose = false;
};

int run_stills(StillsOptions o) {
  FilterParams params;
  for (const auto& kv : o.sets) {
    std::string err;
    if (!set_filter_param(params, kv, err)) {
      std::fprintf(stderr, "mocap stills: --set %s: %s\n", kv.c_str(), err.c_str());
      return 2;
    }
  }
  o.check.use_mag = o.mode == "9d" || o.mode == "9D";
  std::vector<std::vector<ImuSample>> per_sensor;
  daemon::SampleCsvParser parser(o.input);
  try {
    daemon::TextLines in(o.input);
    std::string line;
    ImuSample s;
    while (in.next(line)) {
      const int r = parser.feed_line(line, s);
      if (r < 0) {
        std::fprintf(stderr, "mocap stills: %s\n", parser.error().c_str());
        return 1;
      }
      if (r == 0) continue;
      if (s.sensor_id >= per_sensor.size()) per_sensor.resize(s.sensor_id + 1);
      per_sensor[s.sensor_id].push_back(s);
    }
    if (!in.error().empty()) {
      std::fprintf(stderr, "mocap stills: %s\n", in.error().c_str());
      return 1;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mocap stills: %s\n", e.what());
    return 1;
  }
  if (per_sensor.empty()) {
    std::fprintf(stderr, "mocap stills: %s holds no samples\n", o.input.c_str());
    return 1;
  }
  std::printf("%-14s %6s %6s %8s %7s %8s %7s %8s\n", "sensor", "g", "stands", "rms_deg", "stances",
              "rms_deg", "max_deg", "at_s");
  double sum_stand = 0, sum_stance = 0, all2 = 0;
  int n_stand = 0, n_stance = 0, n_all = 0;
  for (size_t i = 0; i < per_sensor.size(); ++i) {
    const SensorStills r = check_stills(per_sensor[i], params, o.check);
    std::printf("%-14s %6.3f %6d %8.3f %7d %8.3f %7.3f %8.2f\n", parser.sensors()[i].c_str(),
                r.g_m_s2, r.stands, r.stand_rms_deg, r.stances, r.stance_rms_deg, r.max_deg,
                r.max_t_s);
    if (r.stands) sum_stand += r.stand_rms_deg, ++n_stand;
    if (r.stances) sum_stance += r.stance_rms_deg, ++n_stance;
    for (const StillMoment& m : r.moments) {
      all2 += m.err_deg * m.err_deg;
      ++n_all;
      if (o.verbose) std::printf("  %8.2f-%8.2f s  %7.3f deg\n", m.t_begin_s, m.t_end_s, m.err_deg);
    }
  }
  std::printf(
      "MEAN over sensors: stands %.3f deg (%d sensors), stances %.3f deg (%d sensors); "
      "RMS over all %d moments %.3f deg\n",
      n_stand ? sum_stand / n_stand : 0.0, n_stand, n_stance ? sum_stance / n_stance : 0.0,
      n_stance, n_all, n_all ? std::sqrt(all2 / n_all) : 0.0);
  return 0;
}

}  // namespace

void add_stills(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<StillsOptions>();
  CLI::App* c = cli::add_command(
      app, "stills",
      "score the filter's inclination at each sensor's still moments of a sample CSV (at rest "
      "the accelerometer reads gravity alone)");
  c->add_option("INPUT", o->input, "samples CSV (or .csv.gz): t,sensor,gyr_x,...,acc_z[,mag_*]")
      ->required();
  c->add_option("--mode", o->mode, "6d (default) or 9d (with the magnetometer, if any)")
      ->check(CLI::IsMember({"9d", "6d"}, CLI::ignore_case));
  cli::add_multi(*c, "--set", o->sets, "override a filter parameter: --set tau_acc_s=2");
  c->add_option("--gyr-th", o->check.gyr_th_rad_s, "still: |gyr| below this, rad/s");
  c->add_option("--acc-th", o->check.acc_th_m_s2, "still: |acc| within this of g, m/s^2");
  c->add_option("--min-s", o->check.min_s, "shortest still moment, s");
  c->add_option("--onset-s", o->check.onset_s, "scored part of each moment, s");
  c->add_flag("--verbose", o->verbose, "list every moment");
  c->callback([o, &exit_code] { exit_code = run_stills(*o); });
}

}  // namespace mocap::cmd
