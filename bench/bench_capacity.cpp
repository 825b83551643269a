// mocap bench capacity: N simulated WitMotion sensors at R Hz (default 20 x 1 kHz) written to
// real ptys and read by a spawned mocapd (real drivers, pipeline at its default frame rate, JSON
// server) for S seconds. Reports samples written / taken by the pipeline / lost, the daemon's
// CPU use (/proc/PID/stat) as % of one core and the simulator thread's separately, and the
// daemon's resident memory sampled every second (first / last / max VmRSS, VmHWM).
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench.hpp"
#include "daemon_harness.hpp"
#include "mocap/core/cli.hpp"
#include "mocap/core/time.hpp"

namespace mocap::bench {

namespace {

struct DaemonCounts {
  uint64_t samples = 0, ring_drops = 0, rejected = 0, decoder_drops = 0, errors = 0;
  bool ok = false;
};

DaemonCounts counts(const std::string& status) {
  DaemonCounts c;
  try {
    const auto j = nlohmann::json::parse(status);
    c.samples = j.at("samples").get<uint64_t>();
    c.ring_drops = j.at("ring_drops").get<uint64_t>();
    c.rejected = j.at("rejected_samples").get<uint64_t>();
    for (const auto& s : j.at("sensors")) {
      c.decoder_drops += s.at("drops").get<uint64_t>();
      c.errors += s.at("errors").get<uint64_t>();
    }
    c.ok = true;
  } catch (const std::exception&) {
  }
  return c;
}

/// mocap bench capacity's command line (declared in add_capacity).
struct CapacityOptions {
  int sensors = 20;
  double rate_hz = 1000, seconds = 10;
};

int run_capacity(const CapacityOptions& o) {
  const int sensors = o.sensors;
  const double rate = o.rate_hz, seconds = o.seconds;
  const double load_before = load_average_1m();
  RigOptions ro;
  ro.sensors = sensors;
  ro.rate_hz = rate;
  try {
    DaemonRig rig(ro);
    if (!rig.wait_streaming(15)) {
      std::fprintf(stderr, "mocap bench capacity: sensors not streaming within 15 s (log %s)\n",
                   rig.log_path().c_str());
      return 1;
    }
    timespec settle{0, 200'000'000};  // let the warm-up samples reach the pipeline
    ::nanosleep(&settle, nullptr);
    const DaemonCounts c0 = counts(rig.status());
    const double cpu0 = process_cpu_s(rig.pid());
    const double sim_cpu0 = thread_cpu_s();
    // Writer: every 1 ms tick writes every sample that fell due (rate may exceed 1 kHz).
    const int64_t period_ns = static_cast<int64_t>(1e9 / rate);
    const int64_t t0 = monotonic_ns();
    const int64_t end = t0 + static_cast<int64_t>(seconds * 1e9);
    int64_t next_sample = t0, k = 0, next_rss = t0 + 1'000'000'000;
    uint64_t written = 0, short_writes = 0;
    std::vector<double> rss;
    rss.push_back(process_rss_mb(rig.pid()));
    while (next_sample < end) {
      timespec ts{static_cast<time_t>(next_sample / 1'000'000'000),
                  static_cast<long>(next_sample % 1'000'000'000)};
      ::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
      const int64_t now = monotonic_ns();
      while (next_sample <= now && next_sample < end) {
        for (int i = 0; i < sensors; ++i) {
          if (!rig.write_sample(i, 1'000'000'000 + k * period_ns)) ++short_writes;
          ++written;
        }
        ++k;
        next_sample = t0 + k * period_ns;
      }
      if ((k & 255) == 0) rig.answer_host();
      if (now >= next_rss) {
        rss.push_back(process_rss_mb(rig.pid()));
        next_rss += 1'000'000'000;
      }
    }
    const double wall_s = (monotonic_ns() - t0) * 1e-9;
    const double sim_cpu_s = thread_cpu_s() - sim_cpu0;
    const double cpu_s = process_cpu_s(rig.pid()) - cpu0;
    // Let the daemon drain what is in flight, then count.
    timespec drain{0, 300'000'000};
    ::nanosleep(&drain, nullptr);
    const DaemonCounts c1 = counts(rig.status());
    rss.push_back(process_rss_mb(rig.pid()));
    const double hwm = process_hwm_mb(rig.pid());
    rig.stop();
    const uint64_t received = c1.samples - c0.samples;
    const uint64_t lost = written > received ? written - received : 0;
    const double cpu_pct = 100.0 * cpu_s / wall_s;
    const double rss_max = *std::max_element(rss.begin(), rss.end());
    const bool pass = c1.ok && lost == 0 && short_writes == 0 && cpu_pct < 25.0;
    std::printf(
        "{\"benchmark\":\"capacity\",\"path\":\"ptys -> mocapd (witmotion drivers, pipeline, "
        "JSON server)\",\n"
        " \"params\":{\"sensors\":%d,\"rate_hz\":%g,\"seconds\":%g},\"wall_s\":%.3f,\n"
        " \"samples\":{\"written\":%llu,\"received\":%llu,\"lost\":%llu,\"short_writes\":%llu,"
        "\"ring_drops\":%llu,\"decoder_drops\":%llu,\"decoder_errors\":%llu,\"rejected\":%llu},\n"
        " \"daemon_cpu_pct_of_one_core\":%.1f,\"simulator_cpu_pct_of_one_core\":%.1f,\n"
        " \"daemon_rss_mb\":{\"first\":%.1f,\"last\":%.1f,\"max\":%.1f,\"hwm\":%.1f,"
        "\"samples\":%zu},\n"
        " \"goal\":{\"lost\":0,\"daemon_cpu_pct_below\":25},\"pass\":%s,\n"
        " \"load_average_1m\":{\"before\":%.2f,\"after\":%.2f}}\n",
        sensors, rate, seconds, wall_s, static_cast<unsigned long long>(written),
        static_cast<unsigned long long>(received), static_cast<unsigned long long>(lost),
        static_cast<unsigned long long>(short_writes),
        static_cast<unsigned long long>(c1.ring_drops - c0.ring_drops),
        static_cast<unsigned long long>(c1.decoder_drops - c0.decoder_drops),
        static_cast<unsigned long long>(c1.errors - c0.errors),
        static_cast<unsigned long long>(c1.rejected - c0.rejected), cpu_pct,
        100.0 * sim_cpu_s / wall_s, rss.front(), rss.back(), rss_max, hwm, rss.size(),
        pass ? "true" : "false", load_before, load_average_1m());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mocap bench capacity: %s\n", e.what());
    return 1;
  }
}

}  // namespace

void add_capacity(CLI::App& bench, int& exit_code) {
  auto o = std::make_shared<CapacityOptions>();
  CLI::App* c = cli::add_command(bench, "capacity",
                                 "sensors x rate through mocapd without drops, and its CPU use");
  c->add_option("--sensors", o->sensors, "number of simulated sensors")->check(CLI::Range(1, 64));
  c->add_option("--rate", o->rate_hz, "sample rate per sensor, Hz")
      ->check(CLI::Range(1e-9, 4000.0));
  cli::add_deprecated_alias(
      *c, "--seconds", o->seconds,
      c->add_option("--duration", o->seconds, "measured duration, s")->check(CLI::Range(1.0, 1e6)));
  c->callback([o, &exit_code] { exit_code = run_capacity(*o); });
}

}  // namespace mocap::bench
