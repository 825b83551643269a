// mocap bench latency: bytes written to a simulated WitMotion sensor's pty -> the JSON line that
// carries that sample, received by a TCP client on loopback (--protocol slimevr: a SlimeVR
// board's rotation datagram instead, with the WitMotion path measured first as the baseline). A
// spawned mocapd (real drivers, pipeline with publish_every_sample, JSON server) reads N ptys; one
// writer thread writes the sensors round-robin, evenly spread over each sample period, stamping
// monotonic time at each write; a client thread stamps each received line. Each line is matched
// to the write it came from by payload: every frame shows, per sensor, the newest sample's device
// time and number (SensorStatus t_device_ns, seq), and the bench knows what it wrote (WitMotion:
// the device time in its time packet, distinct per sample; SlimeVR: the datagram's packet
// number). Write k of sensor i is matched to the first line received after it whose sensor i
// shows that sample; a sample no line shows is unmatched. With --realtime-priority N (default
// 20) mocapd runs its reader, pipeline and stream threads in SCHED_FIFO, and so do the writer
// (standing in for sensor hardware) and the client; 0 measures normal scheduling.
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "bench.hpp"
#include "daemon_harness.hpp"
#include "mocap/core/cli.hpp"
#include "mocap/core/thread_priority.hpp"
#include "mocap/core/time.hpp"

namespace mocap::bench {

namespace {

struct Line {
  int64_t t_recv_ns;
  int64_t t_frame_ns;  ///< the line's "t": the frame's time (its newest sample's host time, the
                       ///< read time mapped from the device clock, <= read)
  uint32_t first_key;  ///< index of its sensors' keys in the client's key array
};

/// The line's "t" (seconds, host monotonic clock) in ns; -1 if absent.
int64_t frame_time_ns(std::string_view line) {
  static constexpr char kT[] = "\"t\":";
  const size_t pos = line.find(kT);
  if (pos == std::string_view::npos) return -1;
  return static_cast<int64_t>(
      std::llround(std::strtod(line.data() + pos + sizeof kT - 1, nullptr) * 1e9));
}

/// Appends each sensor's `field` (an integer: "seq" or "t_device_ns") to keys, in sensor order,
/// exactly `sensors` of them (a missing one as 0, which no written sample has).
void sensor_keys(std::string_view line, std::string_view field, int sensors,
                 std::vector<uint64_t>& keys) {
  static constexpr std::string_view kSensors = "\"sensors\":[";
  size_t pos = line.find(kSensors);
  for (int i = 0; i < sensors; ++i) {
    uint64_t v = 0;
    if (pos != std::string_view::npos) pos = line.find(field, pos);
    if (pos != std::string_view::npos) {
      pos += field.size();
      std::from_chars(line.data() + pos, line.data() + line.size(), v);
    }
    keys.push_back(v);
  }
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return -1;
  std::sort(v.begin(), v.end());
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(p * (v.size() - 1) + 0.5));
  return v[k];
}

}  // namespace

/// One run: what the JSON reports of it.
struct Measured {
  uint64_t written = 0, unmatched = 0, short_writes = 0;
  size_t lines = 0;
  long long ring_drops = -1;
  std::vector<double> lat_ms, to_read_ms, from_read_ms;
};

/// Spawns the rig, writes `seconds` of samples, matches lines to writes. False + err on failure.
bool measure(const RigOptions& ro, double seconds, Measured& m, std::string& err) {
  const int sensors = ro.sensors;
  const double rate = ro.rate_hz;
  {
    DaemonRig rig(ro);
    if (!rig.wait_streaming(15)) {
      err = "sensors not streaming within 15 s (log " + rig.log_path() + ")";
      return false;
    }
    (void)set_this_thread_realtime(ro.realtime_priority, nullptr);  // the writer (this thread)
    const int fd = connect_loopback(rig.json_port(), 5);
    if (fd < 0) {
      err = "cannot connect to the JSON stream";
      return false;
    }
    // Client: stamps each line as its last byte arrives and keeps what it shows of each sensor.
    const bool slime = ro.protocol == "slimevr";
    const std::string_view key_field = slime ? "\"seq\":" : "\"t_device_ns\":";
    std::vector<Line> lines;
    std::vector<uint64_t> keys;  // per line, `sensors` keys from lines[j].first_key
    const size_t expect_lines = static_cast<size_t>(sensors * rate * (seconds + 2) * 1.5 + 1000);
    lines.reserve(expect_lines);
    keys.reserve(expect_lines * static_cast<size_t>(sensors));
    std::atomic<bool> stop{false};
    std::thread client([&] {
      (void)set_this_thread_realtime(ro.realtime_priority, nullptr);
      std::vector<char> buf(1 << 20);
      size_t have = 0;
      while (!stop) {
        const ssize_t n = ::read(fd, buf.data() + have, buf.size() - have);
        if (n <= 0) break;
        const int64_t now = monotonic_ns();
        have += static_cast<size_t>(n);
        size_t start = 0;
        for (size_t i = have - static_cast<size_t>(n); i < have; ++i) {
          if (buf[i] != '\n') continue;
          const std::string_view line(buf.data() + start, i - start);
          lines.push_back({now, frame_time_ns(line), static_cast<uint32_t>(keys.size())});
          sensor_keys(line, key_field, sensors, keys);
          start = i + 1;
        }
        std::memmove(buf.data(), buf.data() + start, have - start);
        have -= start;
        if (have == buf.size()) have = 0;  // a line longer than 1 MB: drop it
      }
    });
    // Writer: sensor i at t0 + k/rate + i/(rate*N), stamped with the device clock at t0 +
    // k/rate (later than every warm-up sample's, so none shows a warm-up sample's time).
    const int64_t period_ns = static_cast<int64_t>(1e9 / rate);
    const int64_t spacing_ns = period_ns / sensors;
    const int64_t periods = static_cast<int64_t>(seconds * rate);
    struct Write {
      int64_t t_ns;
      uint64_t key;
    };
    std::vector<std::vector<Write>> writes(static_cast<size_t>(sensors));
    for (auto& w : writes)
      w.reserve(static_cast<size_t>(periods));
    uint64_t short_writes = 0;
    rig.keep_alive(0.2);  // the client is connected; the sensors keep talking meanwhile
    const int64_t t0 = monotonic_ns() + period_ns;
    const int64_t t_device0 = rig.device_ns(t0);
    for (int64_t k = 0; k < periods; ++k) {
      for (int i = 0; i < sensors; ++i) {
        const int64_t due = t0 + k * period_ns + i * spacing_ns;
        timespec ts{static_cast<time_t>(due / 1'000'000'000),
                    static_cast<long>(due % 1'000'000'000)};
        ::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
        const int64_t w = monotonic_ns();
        uint64_t key = 0;
        if (!rig.write_sample(i, t_device0 + k * period_ns, &key)) ++short_writes;
        writes[static_cast<size_t>(i)].push_back({w, key});
      }
      if (k % 64 == 0) rig.answer_host();
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    const std::string status = rig.status();
    stop = true;
    ::shutdown(fd, SHUT_RDWR);
    client.join();
    ::close(fd);
    rig.stop();
    // Match: per sensor, write k -> the first line received after it that shows its key (what
    // the bench wrote into that sample). A sensor's keys only grow from line to line, so one
    // forward scan per sensor finds them; a key skipped over was shown by no line.
    std::vector<double> lat_ms;
    lat_ms.reserve(static_cast<size_t>(sensors * periods));
    std::vector<double> to_read_ms, from_read_ms;  // split at the frame's time
    to_read_ms.reserve(lat_ms.capacity());
    from_read_ms.reserve(lat_ms.capacity());
    uint64_t unmatched = 0;
    for (int i = 0; i < sensors; ++i) {
      size_t li = 0;
      const auto key_of = [&](size_t l) {
        return keys[lines[l].first_key + static_cast<size_t>(i)];
      };
      for (const Write& w : writes[static_cast<size_t>(i)]) {
        while (li < lines.size() && (lines[li].t_recv_ns < w.t_ns || key_of(li) < w.key))
          ++li;
        if (li == lines.size() || key_of(li) != w.key) {
          ++unmatched;
          continue;
        }
        lat_ms.push_back((lines[li].t_recv_ns - w.t_ns) * 1e-6);
        if (lines[li].t_frame_ns >= 0) {
          to_read_ms.push_back((lines[li].t_frame_ns - w.t_ns) * 1e-6);
          from_read_ms.push_back((lines[li].t_recv_ns - lines[li].t_frame_ns) * 1e-6);
        }
      }
    }
    m.written = static_cast<uint64_t>(sensors) * static_cast<uint64_t>(periods);
    m.unmatched = unmatched;
    m.short_writes = short_writes;
    m.lines = lines.size();
    if (auto p = status.find("\"ring_drops\":"); p != std::string::npos)
      m.ring_drops = std::atoll(status.c_str() + p + 13);
    m.lat_ms = std::move(lat_ms);
    m.to_read_ms = std::move(to_read_ms);
    m.from_read_ms = std::move(from_read_ms);
  }
  return true;
}

/// `--protocol slimevr`: both paths and the ratio of their p99.
int print_slimevr(const RigOptions& ro, double seconds, const Measured& slime, const Measured& wit,
                  double load_before) {
  const auto stats = [](const Measured& m) {
    char b[400];
    const double mx = m.lat_ms.empty() ? -1 : *std::max_element(m.lat_ms.begin(), m.lat_ms.end());
    std::snprintf(
        b, sizeof b,
        "{\"written\":%llu,\"matched\":%zu,\"unmatched\":%llu,\"short_writes\":%llu,"
        "\"daemon_ring_drops\":%lld,\"latency_ms\":{\"p50\":%.4f,\"p99\":%.4f,\"max\":%.4f}}",
        static_cast<unsigned long long>(m.written), m.lat_ms.size(),
        static_cast<unsigned long long>(m.unmatched),
        static_cast<unsigned long long>(m.short_writes), m.ring_drops, percentile(m.lat_ms, 0.5),
        percentile(m.lat_ms, 0.99), mx);
    return std::string(b);
  };
  const double p99_s = percentile(slime.lat_ms, 0.99), p99_w = percentile(wit.lat_ms, 0.99);
  const double ratio = p99_w > 0 ? p99_s / p99_w : -1;
  // "No worse than WitMotion": within 25 % of its p99 in the same run (run-to-run noise of the
  // p99 on a shared machine is of that order), and every sample matched.
  const bool pass = ratio > 0 && ratio <= 1.25 && slime.unmatched == 0 && !slime.lat_ms.empty();
  std::printf(
      "{\"benchmark\":\"latency\",\"protocol\":\"slimevr\",\"path\":\"UDP datagram from a "
      "tracker board -> mocapd (slimevr device, pipeline publish_every_sample, JSON server) -> TCP "
      "client on loopback; baseline: the same with WitMotion bytes on ptys\",\n"
      " \"params\":{\"sensors\":%d,\"rate_hz\":%g,\"seconds\":%g,\"realtime_priority\":%d},\n"
      " \"slimevr\":%s,\n \"witmotion\":%s,\n"
      " \"p99_ratio_slimevr_to_witmotion\":%.3f,\"goal\":\"ratio <= 1.25, all matched\","
      "\"pass\":%s,\n"
      " \"load_average_1m\":{\"before\":%.2f,\"after\":%.2f}}\n",
      ro.sensors, ro.rate_hz, seconds, ro.realtime_priority, stats(slime).c_str(),
      stats(wit).c_str(), ratio, pass ? "true" : "false", load_before, load_average_1m());
  return 0;
}

/// mocap bench latency's command line (declared in add_latency).
struct LatencyOptions {
  int sensors = 17;      ///< slimevr: 16 unless given
  double rate_hz = 200;  ///< slimevr: 100 unless given
  double seconds = 10;
  int rt_priority = 20;
  std::string protocol = "witmotion";
};

int run_latency(const LatencyOptions& o) {
  const std::string& protocol = o.protocol;
  const bool slime = protocol == "slimevr";
  const int sensors = o.sensors;
  const double rate = o.rate_hz;
  const double seconds = o.seconds;
  const int rt_priority = o.rt_priority;
  // Granted to a probe thread <=> granted to mocapd (same user, same limits). A probe, because
  // the main thread's policy would be inherited by the mocapd it forks.
  std::string rt_error;
  bool rt_granted = false;
  if (rt_priority > 0)
    std::thread([&] { rt_granted = set_this_thread_realtime(rt_priority, &rt_error); }).join();
  if (rt_priority > 0 && !rt_granted)
    std::fprintf(stderr, "mocap bench latency: %s; measuring normal scheduling\n",
                 rt_error.c_str());
  if (!slime && rate > 1000) {
    // WitMotion time packets carry whole milliseconds: faster samples share a device time.
    std::fprintf(stderr, "mocap bench latency: --rate above 1000 Hz needs --protocol slimevr\n");
    return 2;
  }
  const double load_before = load_average_1m();
  RigOptions ro;
  ro.sensors = sensors;
  ro.rate_hz = rate;
  ro.publish_every_sample = true;
  ro.realtime_priority = rt_granted ? rt_priority : 0;
  try {
    Measured m;
    std::string err;
    if (!measure(ro, seconds, m, err)) {
      std::fprintf(stderr, "mocap bench latency: %s\n", err.c_str());
      return 1;
    }
    if (slime) {
      // The same load through SlimeVR boards over UDP, after the WitMotion baseline above.
      RigOptions rs = ro;
      rs.protocol = "slimevr";
      Measured ms;
      if (!measure(rs, seconds, ms, err)) {
        std::fprintf(stderr, "mocap bench latency (slimevr): %s\n", err.c_str());
        return 1;
      }
      return print_slimevr(ro, seconds, ms, m, load_before);
    }
    const auto& lat_ms = m.lat_ms;
    const uint64_t unmatched = m.unmatched, written = m.written, short_writes = m.short_writes;
    const long long ring_drops = m.ring_drops;
    const auto& to_read_ms = m.to_read_ms;
    const auto& from_read_ms = m.from_read_ms;
    const size_t n_lines = m.lines;
    const double p50 = percentile(lat_ms, 0.50), p99 = percentile(lat_ms, 0.99);
    const double mx = lat_ms.empty() ? -1 : *std::max_element(lat_ms.begin(), lat_ms.end());
    const bool pass = !lat_ms.empty() && unmatched == 0 && p50 <= 0.3 && p99 <= 1.0;
    std::printf(
        "{\"benchmark\":\"latency\",\"path\":\"pty bytes -> mocapd (witmotion driver, pipeline "
        "publish_every_sample, JSON server) -> TCP client on loopback\",\n"
        " \"params\":{\"sensors\":%d,\"rate_hz\":%g,\"seconds\":%g,\"realtime_priority\":%d},\n"
        " \"written\":%llu,\"matched\":%zu,\"unmatched\":%llu,\"short_writes\":%llu,"
        "\"json_lines\":%zu,\"daemon_ring_drops\":%lld,\n"
        " \"latency_ms\":{\"p50\":%.4f,\"p99\":%.4f,\"max\":%.4f},\n"
        " \"split_ms\":{\"write_to_sample_t\":{\"p50\":%.4f,\"p99\":%.4f},"
        "\"sample_t_to_client\":{\"p50\":%.4f,\"p99\":%.4f}},\n"
        " \"goal\":{\"p50_ms\":0.3,\"p99_ms\":1.0},\"pass\":%s,\n"
        " \"load_average_1m\":{\"before\":%.2f,\"after\":%.2f}}\n",
        sensors, rate, seconds, ro.realtime_priority, static_cast<unsigned long long>(written),
        lat_ms.size(), static_cast<unsigned long long>(unmatched),
        static_cast<unsigned long long>(short_writes), n_lines, ring_drops, p50, p99, mx,
        percentile(to_read_ms, 0.5), percentile(to_read_ms, 0.99), percentile(from_read_ms, 0.5),
        percentile(from_read_ms, 0.99), pass ? "true" : "false", load_before, load_average_1m());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mocap bench latency: %s\n", e.what());
    return 1;
  }
}

void add_latency(CLI::App& bench, int& exit_code) {
  auto o = std::make_shared<LatencyOptions>();
  CLI::App* c =
      cli::add_command(bench, "latency", "device bytes to the JSON line over TCP, percentiles");
  CLI::Option* sensors = c->add_option("--sensors", o->sensors,
                                       "number of simulated sensors (slimevr: 16 unless given)")
                             ->check(CLI::Range(1, 32));
  CLI::Option* rate =
      c->add_option("--rate", o->rate_hz, "sample rate per sensor, Hz (slimevr: 100 unless given)")
          ->check(CLI::Range(1e-9, 2000.0));
  cli::add_deprecated_alias(
      *c, "--seconds", o->seconds,
      c->add_option("--duration", o->seconds, "measured duration, s")->check(CLI::PositiveNumber));
  c->add_option("--realtime-priority", o->rt_priority,
                "SCHED_FIFO priority for mocapd and the bench threads, 0 = normal")
      ->check(CLI::Range(0, kMaxRealtimePriority));
  c->add_option("--protocol", o->protocol,
                "witmotion (ptys) or slimevr (UDP tracker boards, compared with witmotion in the "
                "same run)")
      ->check(CLI::IsMember({"witmotion", "slimevr"}));
  c->callback([o, sensors, rate, &exit_code] {
    if (o->protocol == "slimevr") {  // the figure: 16 trackers at 100 Hz
      if (sensors->count() == 0) o->sensors = 16;
      if (rate->count() == 0) o->rate_hz = 100;
    }
    exit_code = run_latency(*o);
  });
}

}  // namespace mocap::bench
