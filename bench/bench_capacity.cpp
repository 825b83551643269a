// mocap bench capacity: P performers, each a spawned mocapd (real drivers, pipeline at its default
// frame rate, JSON server) reading N simulated sensors at R Hz for S seconds (default 1 x 20 x
// 1 kHz WitMotion sensors on real ptys; --protocol line-udp: the DIY line protocol, a UDP port
// per sensor; slimevr: SlimeVR boards over UDP). Reports samples written / taken by the
// pipelines / lost, the daemons' CPU use (/proc/PID/stat) as % of one core and per sample, the
// simulator thread's separately, and the daemons' resident memory sampled every second (first /
// last / max VmRSS, VmHWM). Unless --no-baseline, the same load runs first with
// pipeline.read_batch_ms = 0 (every sample read as it arrives): the baseline of the same run.
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
  DaemonCounts& operator+=(const DaemonCounts& o) {
    samples += o.samples, ring_drops += o.ring_drops, rejected += o.rejected;
    decoder_drops += o.decoder_drops, errors += o.errors;
    ok = ok && o.ok;
    return *this;
  }
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
  int sensors = 20;    ///< per performer
  int performers = 1;  ///< daemons
  double rate_hz = 1000, seconds = 10;
  std::string protocol = "witmotion";
  double read_batch_ms = -1;  ///< < 0: mocapd's default
  bool baseline = true;
};

/// One run's figures.
struct Run {
  double read_batch_ms = -1;
  double wall_s = 0, cpu_s = 0, sim_cpu_s = 0;
  uint64_t written = 0, short_writes = 0;
  DaemonCounts c0, c1;
  std::vector<double> rss;  ///< summed over the daemons, every second
  double hwm = 0;
  uint64_t received() const { return c1.samples - c0.samples; }
  uint64_t lost() const { return written > received() ? written - received() : 0; }
  double cpu_pct() const { return 100.0 * cpu_s / wall_s; }
  double us_per_sample() const { return received() ? 1e6 * cpu_s / received() : -1; }
};

DaemonCounts all_counts(const std::vector<std::unique_ptr<DaemonRig>>& rigs) {
  DaemonCounts sum;
  sum.ok = true;
  for (const auto& r : rigs)
    sum += counts(r->status());
  return sum;
}

double all_cpu_s(const std::vector<std::unique_ptr<DaemonRig>>& rigs) {
  double s = 0;
  for (const auto& r : rigs)
    s += process_cpu_s(r->pid());
  return s;
}

double all_rss_mb(const std::vector<std::unique_ptr<DaemonRig>>& rigs) {
  double s = 0;
  for (const auto& r : rigs)
    s += process_rss_mb(r->pid());
  return s;
}

/// Spawns the performers' daemons, writes `seconds` of samples, counts. False + err on failure.
bool measure(const CapacityOptions& o, double read_batch_ms, Run& run, std::string& err) {
  run.read_batch_ms = read_batch_ms;
  RigOptions ro;
  ro.sensors = o.sensors;
  ro.rate_hz = o.rate_hz;
  ro.protocol = o.protocol;
  ro.read_batch_ms = read_batch_ms;
  std::vector<std::unique_ptr<DaemonRig>> rigs;
  for (int p = 0; p < o.performers; ++p)
    rigs.push_back(std::make_unique<DaemonRig>(ro));
  for (const auto& r : rigs)
    if (!r->wait_streaming(30)) {
      err = "sensors not streaming within 30 s; mocapd said:\n" + r->log_tail();
      return false;
    }
  // The sensors keep talking (every 10 ms) while the warm-up's samples reach the pipelines;
  // the count starts 12 ms after the last of them (read at once, drained by the 8.3 ms frame
  // tick) and the run right after: no gap a device clock would take for lost samples.
  int64_t last = 0;
  for (const auto& r : rigs)
    last = r->keep_alive(0.3 / static_cast<double>(rigs.size()));
  const int64_t count_at = last + 12'000'000;
  const timespec settle{static_cast<time_t>(count_at / 1'000'000'000),
                        static_cast<long>(count_at % 1'000'000'000)};
  ::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &settle, nullptr);
  run.c0 = all_counts(rigs);
  const double cpu0 = all_cpu_s(rigs);
  const double sim_cpu0 = thread_cpu_s();
  // Writer: every 1 ms tick writes every sample that fell due (rate may exceed 1 kHz), each
  // stamped with its rig's device clock at the time it fell due.
  const int64_t period_ns = static_cast<int64_t>(1e9 / o.rate_hz);
  const int64_t t0 = monotonic_ns();
  const int64_t end = t0 + static_cast<int64_t>(o.seconds * 1e9);
  int64_t next_sample = t0, k = 0, next_rss = t0 + 1'000'000'000;
  run.rss.push_back(all_rss_mb(rigs));
  while (next_sample < end) {
    timespec ts{static_cast<time_t>(next_sample / 1'000'000'000),
                static_cast<long>(next_sample % 1'000'000'000)};
    ::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
    const int64_t now = monotonic_ns();
    while (next_sample <= now && next_sample < end) {
      for (size_t p = 0; p < rigs.size(); ++p) {
        const int64_t t_device = rigs[p]->device_ns(next_sample);
        for (int i = 0; i < o.sensors; ++i) {
          if (!rigs[p]->write_sample(i, t_device)) ++run.short_writes;
          ++run.written;
        }
      }
      ++k;
      next_sample = t0 + k * period_ns;
    }
    if ((k & 255) == 0)
      for (const auto& r : rigs)
        r->answer_host();
    if (now >= next_rss) {
      run.rss.push_back(all_rss_mb(rigs));
      next_rss += 1'000'000'000;
    }
  }
  run.wall_s = (monotonic_ns() - t0) * 1e-9;
  run.sim_cpu_s = thread_cpu_s() - sim_cpu0;
  run.cpu_s = all_cpu_s(rigs) - cpu0;
  // Let the daemons drain what is in flight, then count.
  timespec drain{0, 300'000'000};
  ::nanosleep(&drain, nullptr);
  run.c1 = all_counts(rigs);
  run.rss.push_back(all_rss_mb(rigs));
  for (const auto& r : rigs)
    run.hwm += process_hwm_mb(r->pid());
  return true;
}

std::string run_json(const Run& r) {
  char batch[32] = "\"default\"";
  if (r.read_batch_ms >= 0) std::snprintf(batch, sizeof batch, "%g", r.read_batch_ms);
  char b[900];
  std::snprintf(
      b, sizeof b,
      "{\"read_batch_ms\":%s,\"wall_s\":%.3f,\n"
      "  \"samples\":{\"written\":%llu,\"received\":%llu,\"lost\":%llu,\"short_writes\":%llu,"
      "\"ring_drops\":%llu,\"decoder_drops\":%llu,\"decoder_errors\":%llu,\"rejected\":%llu},\n"
      "  \"daemon_cpu_pct_of_one_core\":%.1f,\"daemon_cpu_us_per_sample\":%.2f,"
      "\"simulator_cpu_pct_of_one_core\":%.1f,\n"
      "  \"daemon_rss_mb\":{\"first\":%.1f,\"last\":%.1f,\"max\":%.1f,\"hwm\":%.1f,"
      "\"samples\":%zu}}",
      batch, r.wall_s, static_cast<unsigned long long>(r.written),
      static_cast<unsigned long long>(r.received()), static_cast<unsigned long long>(r.lost()),
      static_cast<unsigned long long>(r.short_writes),
      static_cast<unsigned long long>(r.c1.ring_drops - r.c0.ring_drops),
      static_cast<unsigned long long>(r.c1.decoder_drops - r.c0.decoder_drops),
      static_cast<unsigned long long>(r.c1.errors - r.c0.errors),
      static_cast<unsigned long long>(r.c1.rejected - r.c0.rejected), r.cpu_pct(),
      r.us_per_sample(), 100.0 * r.sim_cpu_s / r.wall_s, r.rss.front(), r.rss.back(),
      *std::max_element(r.rss.begin(), r.rss.end()), r.hwm, r.rss.size());
  return b;
}

int run_capacity(const CapacityOptions& o) {
  const double load_before = load_average_1m();
  try {
    std::string err;
    Run base, run;
    if (o.baseline && !measure(o, 0.0, base, err)) {
      std::fprintf(stderr, "mocap bench capacity (baseline): %s\n", err.c_str());
      return 1;
    }
    if (!measure(o, o.read_batch_ms, run, err)) {
      std::fprintf(stderr, "mocap bench capacity: %s\n", err.c_str());
      return 1;
    }
    // The goal: nothing lost, all the daemons together under 10 % of one core (one performer)
    // or under one core (several: "ten performers on one core").
    const double goal_pct = o.performers > 1 ? 100.0 : 10.0;
    const bool pass = run.c0.ok && run.c1.ok && run.lost() == 0 && run.short_writes == 0 &&
                      run.cpu_pct() < goal_pct;
    std::printf(
        "{\"benchmark\":\"capacity\",\"path\":\"%s -> mocapd (drivers, pipeline, JSON server), "
        "one mocapd per performer\",\n"
        " \"params\":{\"performers\":%d,\"sensors_per_performer\":%d,\"sensors\":%d,"
        "\"rate_hz\":%g,\"seconds\":%g,\"protocol\":\"%s\"},\n"
        " \"run\":%s,\n"
        " \"baseline\":%s,\n"
        " \"cpu_ratio_run_to_baseline\":%.3f,\n"
        " \"goal\":{\"lost\":0,\"daemon_cpu_pct_below\":%g},\"pass\":%s,\n"
        " \"load_average_1m\":{\"before\":%.2f,\"after\":%.2f}}\n",
        o.protocol == "witmotion" ? "ptys" : "UDP datagrams", o.performers, o.sensors,
        o.performers * o.sensors, o.rate_hz, o.seconds, o.protocol.c_str(), run_json(run).c_str(),
        o.baseline ? run_json(base).c_str() : "null",
        o.baseline && base.cpu_s > 0 ? run.cpu_s / base.cpu_s * base.wall_s / run.wall_s : -1.0,
        goal_pct, pass ? "true" : "false", load_before, load_average_1m());
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
  c->add_option("--sensors", o->sensors, "number of simulated sensors per performer")
      ->check(CLI::Range(1, 32));
  c->add_option("--performers", o->performers,
                "performers, one mocapd each (the goal is then one core for all)")
      ->check(CLI::Range(1, 64));
  c->add_option("--rate", o->rate_hz, "sample rate per sensor, Hz")
      ->check(CLI::Range(1e-9, 4000.0));
  cli::add_deprecated_alias(
      *c, "--seconds", o->seconds,
      c->add_option("--duration", o->seconds, "measured duration, s")->check(CLI::Range(1.0, 1e6)));
  c->add_option("--protocol", o->protocol,
                "witmotion (ptys), line-udp (line protocol, a UDP port per sensor) or slimevr "
                "(SlimeVR boards over UDP)")
      ->check(CLI::IsMember({"witmotion", "line-udp", "slimevr"}));
  c->add_option("--read-batch-ms", o->read_batch_ms,
                "mocapd's pipeline.read_batch_ms for the run (default: mocapd's)")
      ->check(CLI::Range(0.0, 50.0));
  c->add_flag("!--no-baseline", o->baseline,
              "skip the baseline run (the same load with read_batch_ms = 0)");
  c->callback([o, &exit_code] { exit_code = run_capacity(*o); });
}

}  // namespace mocap::bench
