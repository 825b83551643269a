// Device faults against the real mocapd: four line-protocol sensors on real pseudo-terminals,
// each driven by this test. One stays healthy while the others get garbage bytes, truncated
// frames, a wrong-baud burst, a 10x flood, time-counter rollover and clock jumps, or vanish and
// come back. The daemon must keep every other sensor streaming, keep publishing frames, and
// report each fault in its status. A UDP (Wi-Fi) sensor drops out, returns and sends noise.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <random>
#include <thread>

#include "harness.hpp"
#include "mocap/drivers/line_protocol.hpp"

using namespace mocap::reliability;
using namespace std::chrono_literals;

namespace {

uint64_t samples_of(const nlohmann::json& st) {
  return st.value("samples", uint64_t{0});
}

/// Waits until `name` is streaming again; returns the time it took (or -1 on timeout).
double recovery_s(Daemon& d, const std::string& name, std::chrono::milliseconds timeout) {
  const auto t0 = std::chrono::steady_clock::now();
  const bool ok = wait_until(
      [&] { return sensor_status(d.status(), name).value("state", "") == "streaming"; }, timeout);
  return ok ? std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() : -1;
}

/// After `gone` stopped sending: it is reported (not streaming) within 10 s, and over the next
/// `watch` sensor "a" streams on without drops while frames keep coming.
void expect_reported_while_a_streams(Daemon& d, const std::string& gone,
                                     std::chrono::milliseconds watch) {
  EXPECT_TRUE(
      wait_until([&] { return sensor_status(d.status(), gone).value("state", "") != "streaming"; },
                 std::chrono::seconds(10)))
      << d.status().dump();
  const uint64_t a_drops = sensor_status(d.status(), "a").value("drops", 0ull);
  const uint64_t frame_before = d.status().value("frame", 0ull);
  std::this_thread::sleep_for(watch);
  const auto mid = d.status();
  EXPECT_EQ(sensor_status(mid, "a").value("state", ""), "streaming") << mid.dump();
  EXPECT_EQ(sensor_status(mid, "a").value("drops", 0ull), a_drops);
  EXPECT_GT(mid.value("frame", 0ull), frame_before);
}

}  // namespace

TEST(DeviceFaults, FaultySensorsAreReportedAndTheOthersKeepStreaming) {
  TempDir dir;
  LineSensorPty good(dir.file("good")), noisy(dir.file("noisy")), flood(dir.file("flood")),
      wrap(dir.file("wrap"));
  const int port = free_tcp_port();
  const std::string cfg =
      base_config(dir, port) + line_sensor_toml("good", good.link(), "pelvis") +
      line_sensor_toml("noisy", noisy.link(), "torso") +
      line_sensor_toml("flood", flood.link(), "head") +
      // 16-bit microsecond counter: rolls over every 65.5 ms, i.e. every 6-7 samples.
      line_sensor_toml("wrap", wrap.link(), "thigh_l", "t=us acc=g gyr=dps mag=uT wrap=16");
  LineFeeder::Sensor s_good{&good, 0xffffffffull, 1000},
      s_noisy{&noisy, 0xffffffffull, 0xffffffffull - 1'500'000},
      s_flood{&flood, 0xffffffffull, 9000}, s_wrap{&wrap, 0xffffull, 0};
  LineFeeder feeder({&s_good, &s_noisy, &s_flood, &s_wrap});
  Daemon d(dir, "faults", cfg);
  ASSERT_TRUE(d.wait_ready(15s)) << d.log_text();
  ASSERT_TRUE(wait_until(
      [&] {
        const auto st = d.status();
        for (const char* n : {"good", "noisy", "flood", "wrap"})
          if (sensor_status(st, n).value("state", "") != "streaming") return false;
        return true;
      },
      15s))
      << d.status().dump() << "\n"
      << d.log_text();
  StreamClient client(port);
  ASSERT_TRUE(client.connected());

  // Faults, one after another on the noisy sensor (whose 32-bit clock also rolls over and then
  // jumps forward 5 s and back 3 s), while flood floods at 10x and wrap's 16-bit clock rolls over
  // every 65 ms.
  const auto before = d.status();
  const uint64_t good_before = s_good.written.load();
  s_flood.mode = FaultMode::flood;
  for (FaultMode m :
       {FaultMode::garbage, FaultMode::truncated, FaultMode::wrong_baud, FaultMode::glitch}) {
    s_noisy.mode = m;
    std::this_thread::sleep_for(700ms);
  }
  s_noisy.mode = FaultMode::normal;
  for (int64_t jump_us : {int64_t{0}, int64_t{5'000'000}, int64_t{-3'000'000}}) {
    feeder.jump(1, jump_us);
    std::this_thread::sleep_for(400ms);
  }
  s_flood.mode = FaultMode::normal;
  std::this_thread::sleep_for(500ms);
  const auto after = d.status();
  const uint64_t good_written = s_good.written.load() - good_before;

  // The daemon reports the noisy sensor's errors and keeps every sensor (and frames) going.
  EXPECT_GT(sensor_status(after, "noisy").value("errors", 0ull),
            sensor_status(before, "noisy").value("errors", 0ull))
      << after.dump();
  // Every sensor streams (a loaded machine may stall a reader thread past the 250 ms stale
  // time for a moment: allow it to catch up, but a sensor lost for good fails).
  const bool all_streaming = wait_until(
      [&] {
        const auto st = d.status();
        for (const char* n : {"good", "noisy", "flood", "wrap"})
          if (sensor_status(st, n).value("state", "") != "streaming") return false;
        return true;
      },
      10s);
  EXPECT_TRUE(all_streaming) << d.status().dump() << "\n" << d.log_text();
  EXPECT_GT(after.value("frame", 0ull), before.value("frame", 0ull) + 100);
  EXPECT_GT(samples_of(after), samples_of(before) + good_written);
  // The clock jumps are reported (a 16-bit rollover is not a jump: wrap stays at 0).
  EXPECT_GT(sensor_status(after, "noisy").value("clock_resets", 0ull), 0u) << after.dump();
  EXPECT_EQ(sensor_status(after, "good").value("clock_resets", 1ull), 0u) << after.dump();
  EXPECT_EQ(sensor_status(after, "wrap").value("clock_resets", 1ull), 0u) << after.dump();
  // Readings beyond a sensor's range (the glitches) are counted per sensor.
  EXPECT_GT(sensor_status(after, "noisy").value("implausible", 0ull), 0u) << after.dump();
  EXPECT_EQ(sensor_status(after, "good").value("implausible", 1ull), 0u) << after.dump();
  EXPECT_EQ(sensor_status(after, "good").value("saturated", 1ull), 0u) << after.dump();
  // No sample of the healthy sensor was lost by the pipeline: its ring never overflowed and
  // the decoder saw no errors on it.
  EXPECT_EQ(sensor_status(after, "good").value("errors", 1ull), 0u) << after.dump();
  EXPECT_EQ(sensor_status(after, "good").value("drops", 1ull), 0u) << after.dump();
  // Stream clients kept receiving valid JSON throughout.
  EXPECT_GT(client.lines(), 100u);
  EXPECT_EQ(client.bad_lines(), 0u);
  EXPECT_TRUE(d.running());

  std::printf(
      "[figures] faults window: good sensor wrote %llu samples; status: flood rate %.1f "
      "Hz, noisy errors %llu, wrap state %s, pipeline ring_drops %llu -> %llu, rejected "
      "%llu; stream client %llu lines, %llu frames skipped\n",
      static_cast<unsigned long long>(good_written),
      sensor_status(after, "flood").value("rate_hz", 0.0),
      static_cast<unsigned long long>(sensor_status(after, "noisy").value("errors", 0ull)),
      sensor_status(after, "wrap").value("state", "").c_str(),
      static_cast<unsigned long long>(before.value("ring_drops", 0ull)),
      static_cast<unsigned long long>(after.value("ring_drops", 0ull)),
      static_cast<unsigned long long>(after.value("rejected_samples", 0ull)),
      static_cast<unsigned long long>(client.lines()),
      static_cast<unsigned long long>(client.frame_gaps()));
  EXPECT_EQ(d.quit(), 0) << d.log_text();
}

TEST(DeviceFaults, DeviceThatDisappearsIsReportedAndRecovers) {
  TempDir dir;
  LineSensorPty a(dir.file("a")), b(dir.file("b"));
  const int port = free_tcp_port();
  const std::string cfg = base_config(dir, port) + line_sensor_toml("a", a.link(), "pelvis") +
                          line_sensor_toml("b", b.link(), "torso");
  LineFeeder::Sensor sa{&a, 0xffffffffull, 1000}, sb{&b, 0xffffffffull, 1000};
  LineFeeder feeder({&sa, &sb});
  Daemon d(dir, "vanish", cfg);
  ASSERT_TRUE(d.wait_ready(15s)) << d.log_text();
  ASSERT_GE(recovery_s(d, "b", 15s), 0) << d.log_text();

  for (int round = 0; round < 3; ++round) {
    // Unplug: the pty is closed (the driver sees a hang-up) and no data arrives.
    sb.mode = FaultMode::silent;
    b.vanish();
    // Reported; meanwhile the other sensor streams and frames keep coming.
    expect_reported_while_a_streams(d, "b", 500ms);
    // Plug back in at the same path.
    b.reappear();
    sb.mode = FaultMode::normal;
    const double rec = recovery_s(d, "b", 15s);
    EXPECT_GE(rec, 0) << "sensor b did not come back\n" << d.log_text();
    EXPECT_EQ(sensor_status(d.status(), "b").value("reconnects", 0ull),
              static_cast<uint64_t>(round + 1));
    std::printf("[figures] vanish round %d: recovered streaming %.2f s after reappearing\n", round,
                rec);
  }
  EXPECT_NE(d.log_text().find("lost"), std::string::npos) << "the loss is logged";
  EXPECT_EQ(d.quit(), 0) << d.log_text();
}

namespace {

/// A Wi-Fi sensor: line-protocol datagrams to the daemon's UDP port at 100 Hz from its own
/// thread, with the same fault modes as the pty feeder (silent = radio drop-out).
class UdpLineSender {
 public:
  explicit UdpLineSender(int port) : fd_(::socket(AF_INET, SOCK_DGRAM, 0)) {
    to_.sin_family = AF_INET;
    to_.sin_port = htons(static_cast<uint16_t>(port));
    to_.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    thread_ = std::thread([this] { run(); });
  }
  ~UdpLineSender() {
    stop_ = true;
    thread_.join();
    ::close(fd_);
  }
  std::atomic<FaultMode> mode{FaultMode::normal};
  std::atomic<uint64_t> garbage_sent{0};

 private:
  void send(const std::string& bytes) {
    ::sendto(fd_, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&to_),
             sizeof to_);
  }
  void run() {
    uint64_t t_us = 1000, tick = 0;
    std::mt19937 rng(7);
    auto next = std::chrono::steady_clock::now();
    while (!stop_) {
      next += 10ms;
      std::this_thread::sleep_until(next);
      const FaultMode m = mode.load();
      t_us += 10'000;
      ++tick;
      if (m == FaultMode::silent) continue;
      if (m == FaultMode::garbage) {  // a datagram of noise, and now and then a huge one
        std::string junk(tick % 10 == 0 ? 60'000 : 1 + rng() % 200, '\0');
        for (char& c : junk)
          c = static_cast<char>(rng());
        send(junk);
        ++garbage_sent;
      }
      const double phase = 0.01 * static_cast<double>(tick);
      const std::array<double, 9> v{0.0,  0.0, 1.0,  0.0, 0.0, 17.0 * std::cos(phase),
                                    20.0, 0.0, -40.0};
      send(mocap::line::format_line(t_us, v, true));
    }
  }
  int fd_;
  sockaddr_in to_{};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace

TEST(DeviceFaults, UdpSensorDropOutAndNoiseAreReportedAndItRecovers) {
  TempDir dir;
  LineSensorPty a(dir.file("a"));
  LineFeeder::Sensor sa{&a, 0xffffffffull, 1000};
  LineFeeder feeder({&sa});
  const int udp_port = free_udp_port();
  const std::string cfg =
      base_config(dir, free_tcp_port()) + line_sensor_toml("a", a.link(), "pelvis") +
      line_sensor_toml("w", "udp:127.0.0.1:" + std::to_string(udp_port), "torso");
  Daemon d(dir, "udp", cfg);
  ASSERT_TRUE(d.wait_ready(15s)) << d.log_text();
  UdpLineSender w(udp_port);
  ASSERT_GE(recovery_s(d, "w", 15s), 0) << d.log_text();

  for (int round = 0; round < 2; ++round) {
    // Radio drop-out: the datagrams stop. The sensor is reported, the other one streams on.
    w.mode = FaultMode::silent;
    expect_reported_while_a_streams(d, "w", 700ms);
    w.mode = FaultMode::normal;
    const double rec = recovery_s(d, "w", 10s);
    EXPECT_GE(rec, 0) << "the UDP sensor did not come back\n" << d.log_text();
    std::printf("[figures] udp drop-out round %d: streaming again %.2f s after data resumed\n",
                round, rec);
  }

  // Noise datagrams (1-200 random bytes, every tenth 60 kB) between the good ones: counted as
  // errors, the good datagrams still decode, the daemon and the other sensor carry on.
  const uint64_t errors_before = sensor_status(d.status(), "w").value("errors", 0ull);
  const uint64_t samples_before = d.status().value("samples", 0ull);
  w.mode = FaultMode::garbage;
  std::this_thread::sleep_for(1s);
  w.mode = FaultMode::normal;
  std::this_thread::sleep_for(300ms);
  const auto after = d.status();
  EXPECT_GT(sensor_status(after, "w").value("errors", 0ull), errors_before) << after.dump();
  EXPECT_EQ(sensor_status(after, "w").value("state", ""), "streaming") << after.dump();
  EXPECT_EQ(sensor_status(after, "a").value("state", ""), "streaming") << after.dump();
  EXPECT_GT(after.value("samples", 0ull), samples_before + 100);
  std::printf("[figures] udp noise: %llu junk datagrams -> %llu errors reported\n",
              static_cast<unsigned long long>(w.garbage_sent.load()),
              static_cast<unsigned long long>(sensor_status(after, "w").value("errors", 0ull) -
                                              errors_before));
  EXPECT_EQ(d.quit(), 0) << d.log_text();
}
