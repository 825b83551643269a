// End to end over real pseudo-terminals and UDP sockets: a simulated device thread emits a
// protocol's bytes, the real driver (transport, reader thread, decoder) decodes them, and the
// samples are checked against the simulated truth; vanish/return and fault injection included.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <filesystem>

#include "collect_sink.hpp"
#include "mocap/devsim/sim_device.hpp"

using namespace mocap;

namespace {

struct Tolerance {
  double gyr_rad_s, acc_m_s2, mag_uT, q_rad;
};

std::string temp_link(const char* name) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("mocap_drv_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

/// Compares every decoded sample with the truth at its device time; returns the max errors.
/// device_origin_ns: the device clock reading at simulated time 0.
Tolerance check_against_truth(const std::vector<ImuSample>& got, const Motion& m, uint8_t fields,
                              int64_t device_origin_ns = 0) {
  Tolerance e{0, 0, 0, 0};
  int64_t last_host = INT64_MIN;
  for (const auto& s : got) {
    EXPECT_EQ(s.valid & fields, fields);
    EXPECT_GE(s.t_host_ns, last_host);
    last_host = s.t_host_ns;
    const ImuSample t = m.at(s.t_device_ns - device_origin_ns);
    e.gyr_rad_s = std::max(e.gyr_rad_s, (s.gyr_rad_s - t.gyr_rad_s).cwiseAbs().maxCoeff());
    e.acc_m_s2 = std::max(e.acc_m_s2, (s.acc_m_s2 - t.acc_m_s2).cwiseAbs().maxCoeff());
    e.mag_uT = std::max(e.mag_uT, (s.mag_uT - t.mag_uT).cwiseAbs().maxCoeff());
    if (fields & kFieldQuat)
      e.q_rad = std::max(e.q_rad, s.q_device_sensor.angularDistance(t.q_device_sensor));
  }
  return e;
}

}  // namespace

TEST(E2eSerial, LineOverPtyWithDropsAndGarbage) {
  SimOptions so{.protocol = "line",
                .rate_hz = 200,
                .motion = "rotate",
                .pty_link = temp_link("line0"),
                .drop_every = 37,
                .garbage_every = 23};
  SimulatedDevice sim(so);
  sim.start();
  DeviceSpec spec{.name = "line0", .protocol = "line", .port = sim.path()};
  auto dev = make_device(spec, Logger(test::g_log_sink, "test", LogLevel::warn));
  test::CollectSink sink;
  dev->start(sink);
  ASSERT_TRUE(sink.wait_for([&] { return sink.count() >= 400; }));
  dev->stop();
  sim.stop();
  const auto got = sink.snapshot();
  const auto err = check_against_truth(got, sim.motion(), kFieldGyr | kFieldAcc | kFieldMag);
  EXPECT_LT(err.gyr_rad_s, 1e-4);
  EXPECT_LT(err.acc_m_s2, 1e-4);
  EXPECT_LT(err.mag_uT, 1e-3);
  // Drops: every device sample between the first and the last decoded one that did not arrive
  // (withheld by the simulator, or destroyed by the injected garbage) must be counted.
  const int64_t period = 5'000'000;
  const int64_t k0 = got.front().t_device_ns / period + 1, k1 = got.back().t_device_ns / period + 1;
  const uint64_t expected_drops = static_cast<uint64_t>(k1 - k0 + 1) - got.size();
  const uint64_t withheld = static_cast<uint64_t>(k1 / 37 - k0 / 37);
  const auto st = dev->stats().decoder;
  EXPECT_EQ(st.dropped_samples, expected_drops);
  EXPECT_GE(st.dropped_samples, withheld);
  EXPECT_GT(st.resyncs, 0u);
  std::printf(
      "line/pty: %zu samples, max err gyr %.2e rad/s acc %.2e m/s2, drops %llu (expected %llu), "
      "resyncs %llu\n",
      got.size(), err.gyr_rad_s, err.acc_m_s2, (unsigned long long)st.dropped_samples,
      (unsigned long long)expected_drops, (unsigned long long)st.resyncs);
}

TEST(E2eSerial, WitmotionOverPtyIsConfiguredByTheDriver) {
  // The simulated WT901 starts at its factory defaults (10 Hz, no quaternion, no time packet);
  // the driver's set-up must unlock it and switch on time + quaternion at 100 Hz.
  SimOptions so{.protocol = "witmotion",
                .rate_hz = 10,
                .motion = "rotate",
                .pty_link = temp_link("wt0"),
                .corrupt_every = 50};
  SimulatedDevice sim(so);
  sim.start();
  // device_baud exercises the baud change: device command, host follows (termios on the pty).
  DeviceSpec spec{.name = "wt0",
                  .protocol = "witmotion",
                  .port = sim.path(),
                  .rate_hz = 100,
                  .options = {{"device_baud", "115200"}}};
  auto dev = make_device(spec, Logger(test::g_log_sink, "test", LogLevel::warn));
  test::CollectSink sink;
  dev->start(sink);
  ASSERT_TRUE(sink.wait_for([&] {
    const auto s = sink.snapshot();
    return std::count_if(s.begin(), s.end(), [](const ImuSample& x) {
             return x.has(kFieldQuat) && x.t_device_ns > 0;
           }) >= 150;
  }));
  dev->stop();
  sim.stop();
  std::vector<ImuSample> configured;
  for (const auto& s : sink.snapshot())
    if (s.has(kFieldQuat) && s.t_device_ns > 0) configured.push_back(s);
  // Device time from the 0x50 packets: 10 ms steps once at 100 Hz.
  int steps10 = 0;
  for (std::size_t i = 1; i < configured.size(); ++i)
    steps10 += configured[i].t_device_ns - configured[i - 1].t_device_ns == 10'000'000;
  EXPECT_GT(steps10, 100);
  const auto err =
      check_against_truth(configured, sim.motion(), kFieldGyr | kFieldAcc | kFieldMag | kFieldQuat);
  EXPECT_LT(err.gyr_rad_s, 0.0011);
  EXPECT_LT(err.acc_m_s2, 0.005);
  EXPECT_LT(err.mag_uT, 0.51);
  EXPECT_LT(err.q_rad, 2e-3);
  const auto st = dev->stats().decoder;
  EXPECT_GT(st.checksum_errors, 0u);
  std::printf(
      "witmotion/pty: %zu samples, err gyr %.2e acc %.2e mag %.2f q %.2e rad, checksum errors "
      "%llu\n",
      configured.size(), err.gyr_rad_s, err.acc_m_s2, err.mag_uT, err.q_rad,
      (unsigned long long)st.checksum_errors);
}

TEST(E2eSerial, VanishedPtyIsReportedAndReopened) {
  SimOptions so{.protocol = "line", .rate_hz = 100, .pty_link = temp_link("vanish0")};
  SimulatedDevice sim(so);
  sim.start();
  DeviceSpec spec{.name = "v0", .protocol = "line", .port = sim.path()};
  auto dev = make_device(spec, Logger(test::g_log_sink, "test", LogLevel::error));
  test::CollectSink sink;
  dev->start(sink);
  ASSERT_TRUE(sink.wait_for([&] { return sink.count() >= 50; }));
  const int64_t t_vanish = monotonic_ns();
  sim.vanish();
  ASSERT_TRUE(sink.wait_for([&] {
    const auto ev = sink.events_snapshot();
    return !ev.empty() && !ev.back().connected;
  }));
  const double detect_ms = (sink.events_snapshot().back().t_ns - t_vanish) * 1e-6;
  const std::size_t before = sink.count();
  sim.reappear();
  ASSERT_TRUE(sink.wait_for([&] { return sink.count() >= before + 50; }));
  dev->stop();
  sim.stop();
  EXPECT_EQ(dev->stats().reconnects, 1u);
  const auto ev = sink.events_snapshot();
  EXPECT_TRUE(ev.back().connected);
  std::printf("vanish: detected after %.1f ms (%s); reopened, reconnects=%llu\n", detect_ms,
              ev[ev.size() - 2].reason.c_str(), (unsigned long long)dev->stats().reconnects);
}

TEST(E2eSerial, LineOverUdp) {
  const std::string addr = "127.0.0.1:" + std::to_string(test::free_loopback_port(SOCK_DGRAM));
  DeviceSpec spec{.name = "u0", .protocol = "line", .port = "udp:" + addr};
  auto dev = make_device(spec, Logger(test::g_log_sink, "test", LogLevel::warn));
  test::CollectSink sink;
  dev->start(sink);
  ASSERT_TRUE(sink.wait_for([&] { return !sink.events_snapshot().empty(); }));  // bound
  SimOptions so{.protocol = "line", .rate_hz = 200, .motion = "rotate", .udp = addr};
  SimulatedDevice sim(so);
  sim.start();
  ASSERT_TRUE(sink.wait_for([&] { return sink.count() >= 200; }));
  sim.stop();
  // Silence is reported as a disconnection.
  ASSERT_TRUE(sink.wait_for([&] {
    const auto ev = sink.events_snapshot();
    return !ev.empty() && !ev.back().connected;
  }));
  dev->stop();
  const auto err =
      check_against_truth(sink.snapshot(), sim.motion(), kFieldGyr | kFieldAcc | kFieldMag);
  EXPECT_LT(err.gyr_rad_s, 1e-4);
  EXPECT_EQ(dev->stats().decoder.dropped_samples, 0u);
}

TEST(E2eSerial, BadSpecsGetClearErrors) {
  Logger log(test::g_log_sink, "test", LogLevel::off);
  EXPECT_THROW(make_device({.name = "x", .protocol = "nope", .port = "/dev/null"}, log),
               std::invalid_argument);
  EXPECT_THROW(make_device({.name = "x", .protocol = "line", .port = "hid:zz:1"}, log),
               std::invalid_argument);
  EXPECT_THROW(make_device({.name = "x", .protocol = "line", .port = ""}, log),
               std::invalid_argument);
  EXPECT_THROW(
      make_device({.name = "x", .protocol = "line", .port = "/dev/null", .axis_remap = "x,q,z"},
                  log),
      std::invalid_argument);
}

TEST(E2eSerial, XbusOverPtyConfiguredWithRolloversDropsAndGarbage) {
  // The simulated MTi starts streaming at 50 Hz; the driver must switch it to config mode,
  // set 100 Hz output and go back to measurement. Its packet counter and SampleTimeFine start
  // just before their wrap points so both roll over during the test.
  SimOptions so{.protocol = "xbus",
                .rate_hz = 50,
                .motion = "rotate",
                .options = {{"counter_start", "65450"}, {"time_start_ticks", "4294962296"}},
                .pty_link = temp_link("mti0"),
                .drop_every = 41,
                .garbage_every = 29,
                .corrupt_every = 53};
  SimulatedDevice sim(so);
  sim.start();
  DeviceSpec spec{.name = "mti0",
                  .protocol = "xbus",
                  .port = sim.path(),
                  .rate_hz = 100,
                  .options = {{"mag_scale_uT", "50"}}};
  auto dev = make_device(spec, Logger(test::g_log_sink, "test", LogLevel::warn));
  test::CollectSink sink;
  dev->start(sink);
  ASSERT_TRUE(sink.wait_for([&] { return sink.count() >= 250; }));
  dev->stop();
  sim.stop();
  const auto got = sink.snapshot();
  const auto err =
      check_against_truth(got, sim.motion(), kFieldGyr | kFieldAcc | kFieldMag | kFieldQuat,
                          int64_t{4294962296} * 100'000);
  // float32 on the wire: relative precision 6e-8.
  EXPECT_LT(err.gyr_rad_s, 1e-6);
  EXPECT_LT(err.acc_m_s2, 1e-5);
  EXPECT_LT(err.mag_uT, 1e-4);
  EXPECT_LT(err.q_rad, 1e-6);
  // Device time unwrapped across the 2^32-tick rollover: strictly increasing, 10 ms steps at 100
  // Hz.
  int steps10 = 0;
  for (std::size_t i = 1; i < got.size(); ++i) {
    EXPECT_GT(got[i].t_device_ns, got[i - 1].t_device_ns);
    steps10 += got[i].t_device_ns - got[i - 1].t_device_ns == 10'000'000;
  }
  EXPECT_GT(steps10, 150);
  const auto st = dev->stats().decoder;
  // Every counter step that skipped is a drop; samples lost to garbage/corruption count too.
  uint64_t missing = 0;
  for (std::size_t i = 1; i < got.size(); ++i)
    missing += got[i].seq - got[i - 1].seq - 1;
  EXPECT_EQ(st.dropped_samples, missing);
  EXPECT_GT(st.dropped_samples, 0u);
  EXPECT_GT(st.checksum_errors + st.resyncs, 0u);
  std::printf(
      "xbus/pty: %zu samples, err gyr %.1e acc %.1e q %.1e, drops %llu, checksum %llu, resyncs "
      "%llu\n",
      got.size(), err.gyr_rad_s, err.acc_m_s2, err.q_rad, (unsigned long long)st.dropped_samples,
      (unsigned long long)st.checksum_errors, (unsigned long long)st.resyncs);
}

TEST(E2eSerial, MocapSimulateCommandServesTheDriver) {
  // The CLI prints the pty path; the driver reads the WitMotion stream it emits.
  const std::string cmd =
      std::string(MOCAP_BINARY_DIR) +
      "/bin/mocap simulate --protocol witmotion --pty --rate 50 --duration 3 2>/dev/null";
  FILE* p = ::popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  char line[256] = {0};
  ASSERT_NE(std::fgets(line, sizeof line, p), nullptr);
  std::string path(line);
  ASSERT_EQ(path.rfind("pty: ", 0), 0u) << path;
  path = path.substr(5, path.find('\n') - 5);
  DeviceSpec spec{.name = "cli", .protocol = "witmotion", .port = path, .rate_hz = 100};
  auto dev = make_device(spec, Logger(test::g_log_sink, "test", LogLevel::error));
  test::CollectSink sink;
  dev->start(sink);
  const bool ok = sink.wait_for([&] { return sink.count() >= 100; });
  dev->stop();
  ::pclose(p);
  ASSERT_TRUE(ok);
  // Default motion is "rotate": the decoded yaw rate is 90 deg/s about z while roll is small.
  const auto got = sink.snapshot();
  EXPECT_TRUE(std::any_of(got.begin(), got.end(), [](const ImuSample& s) {
    return s.has(kFieldGyr) && std::abs(s.gyr_rad_s.norm() - M_PI / 2) < 0.6;
  }));
}
