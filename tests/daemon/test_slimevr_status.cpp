// What a sensor says about itself reaches the daemon's status: the pipeline keeps each sensor's
// newest telemetry for status(); a sensor whose device reported it gone shows "disconnected",
// one merely silent "stale"; and end to end over real UDP, a simulated SlimeVR board (`mocap
// simulate --protocol slimevr`) reporting 3.7 V / 80 % and -60 dBm shows them in `mocapctl
// status --json` (and the table), then shows disconnected, its last battery kept, once it stops.
#include <gtest/gtest.h>

#include <filesystem>

#include "../common/e2e_process.hpp"
#include "../common/free_port.hpp"
#include "mocap/daemon/pipeline.hpp"
#include "test_engine.hpp"

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using namespace mocap;
using namespace mocap::daemon;

namespace {

struct LastFrame final : mocap::outputs::Output {
  PoseFrame frame;
  void on_frame(const PoseFrame& f) override { frame = f; }
};

ImuSample gyro_sample(uint16_t id, int64_t t_ns) {
  ImuSample s;
  s.sensor_id = id;
  s.t_host_ns = t_ns;
  s.valid = kFieldGyr | kFieldAcc;
  s.acc_m_s2 = {0, 0, 9.81};
  return s;
}

}  // namespace

TEST(SensorLinkState, ASensorWhoseDeviceReportedItGoneIsDisconnectedNotStale) {
  test::GyroEngine eng;
  PipelineConfig pc;
  pc.rate_hz = 50;
  pc.stale_after_ms = 100;
  PipelineCore core(pc, CalibrationConfig{}, {{"a", 0}, {"b", 3}}, eng);
  LastFrame sink;
  core.add_sink(&sink);
  core.set_connected(0, true);
  core.set_connected(1, true);
  int64_t t = 0;
  for (; t <= 500'000'000; t += 10'000'000) {
    core.advance_clock_to(t);
    core.process(gyro_sample(0, t));
    core.process(gyro_sample(1, t));
  }
  EXPECT_EQ(sink.frame.sensors[0].state, kStreaming);
  // Both fall silent; only a's device says its link is gone (a SlimeVR board's 3 s timeout).
  core.set_connected(0, false);
  for (; t <= 1'500'000'000; t += 10'000'000)
    core.advance_clock_to(t);
  EXPECT_EQ(sink.frame.sensors[0].state, kDisconnected);
  EXPECT_EQ(sink.frame.sensors[1].state, kStale);
  // It comes back: streaming again.
  core.set_connected(0, true);
  core.process(gyro_sample(0, t));
  core.advance_clock_to(t + 40'000'000);
  EXPECT_EQ(sink.frame.sensors[0].state, kStreaming);
}

TEST(SensorTelemetryStatus, ThePipelineKeepsEachSensorsNewestReportForStatus) {
  test::GyroEngine eng;
  PipelineConfig pc;
  LogSink logs(stderr);
  Pipeline p(pc, CalibrationConfig{}, {{"a", 0}, {"b", 3}}, eng,
             Logger(logs, "p", LogLevel::error));
  SensorTelemetry t;
  t.battery_fraction = 0.5f;
  SensorTelemetry::set(t.board, "SlimeVR");
  p.on_telemetry(1, t);
  t.battery_fraction = 0.4f;
  p.on_telemetry(1, t);
  p.on_telemetry(kMaxSensors, t);  // no such sensor: ignored
  const PipelineStatus st = p.status();
  EXPECT_FALSE(st.telemetry[0].any());
  EXPECT_FLOAT_EQ(st.telemetry[1].battery_fraction, 0.4f);
  EXPECT_STREQ(st.telemetry[1].board, "SlimeVR");
}

namespace {

nlohmann::json status_json(const std::string& sock, const fs::path& dir) {
  std::string out;
  if (test::run_program({test::kBinDir + "mocapctl", "--socket", sock, "status", "--json"},
                        (dir / "status.out").string(), &out) != 0)
    return {};
  return nlohmann::json::parse(out, nullptr, false);
}

const nlohmann::json* sensor(const nlohmann::json& st, const std::string& name) {
  if (!st.is_object() || !st.contains("sensors")) return nullptr;
  for (const auto& s : st["sensors"])
    if (s.value("name", "") == name) return &s;
  return nullptr;
}

}  // namespace

TEST(SlimeVrStatus, BatteryAndSignalOfASimulatedTrackerReachMocapctlStatus) {
  const fs::path dir =
      fs::temp_directory_path() / ("mocap-slime-status-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string sock = (dir / "ctl.sock").string();
  const std::string server = "127.0.0.1:" + std::to_string(test::free_loopback_port(SOCK_DGRAM));
  const std::string mac = "02:5E:00:00:00:77";
  {
    std::ofstream cfg(dir / "rig.toml");
    cfg << "[filter]\nuse_mag = false\n[outputs.json]\nenabled = false\n";
    for (int k = 0; k < 2; ++k)
      cfg << "[[sensor]]\nname = \"" << (k ? "thigh_l" : "pelvis") << "\"\ndriver = \"slimevr\"\n"
          << "port = \"udp:" << server << "\"\nsegment = \"" << (k ? "thigh_l" : "pelvis")
          << "\"\noptions = { mac = \"" << mac << "\", tracker = " << k << " }\n";
  }
  const pid_t d =
      test::spawn({test::kBinDir + "mocapd", "--config", (dir / "rig.toml").string(), "--set",
                   "daemon.control_socket=" + sock, "--set",
                   "outputs.posture.shm_name=/mocap-slime-status-" + std::to_string(getpid())},
                  (dir / "mocapd.log").string());
  ASSERT_GT(d, 0);
  const pid_t sim = test::spawn({test::kBinDir + "mocap",
                                 "simulate",
                                 "--protocol",
                                 "slimevr",
                                 "--udp",
                                 server,
                                 "--option",
                                 "mac=" + mac,
                                 "--option",
                                 "sensors=2",
                                 "--option",
                                 "battery_v=3.7",
                                 "--option",
                                 "battery_pct=80",
                                 "--option",
                                 "rssi=-60",
                                 "--option",
                                 "temperature=31.5",
                                 "--motion",
                                 "static",
                                 "--duration",
                                 "60"},
                                (dir / "sim.log").string());
  ASSERT_GT(sim, 0);

  nlohmann::json st;
  bool reported = false;
  for (int i = 0; i < 150 && !reported; ++i) {
    std::this_thread::sleep_for(100ms);
    st = status_json(sock, dir);
    const auto* a = sensor(st, "pelvis");
    const auto* b = sensor(st, "thigh_l");
    reported = a && b && a->contains("battery_pct") && a->contains("rssi_dbm") &&
               b->contains("temperature_c") && (*a)["state"] == "streaming";
  }
  ASSERT_TRUE(reported) << st.dump() << test::slurp_file((dir / "mocapd.log.err").string());
  for (const char* name : {"pelvis", "thigh_l"}) {
    const nlohmann::json& s = *sensor(st, name);
    EXPECT_DOUBLE_EQ(s["battery_pct"].get<double>(), 80) << name;
    EXPECT_DOUBLE_EQ(s["battery_v"].get<double>(), 3.7);
    EXPECT_DOUBLE_EQ(s["rssi_dbm"].get<double>(), -60);
    EXPECT_DOUBLE_EQ(s["temperature_c"].get<double>(), 31.5);
    EXPECT_EQ(s["board"], "SlimeVR");
    EXPECT_EQ(s["imu"], "BMI270");
    EXPECT_EQ(s["mcu"], "ESP8266");
    EXPECT_EQ(s["firmware"], "0.6.0-sim");
    EXPECT_EQ(s["address"], mac);
    EXPECT_TRUE(s.contains("reconnects")) << "its device's counters (the port's shared device)";
  }
  // The table of `mocapctl status` says the same in words.
  std::string table;
  ASSERT_EQ(test::run_program({test::kBinDir + "mocapctl", "--socket", sock, "status"},
                              (dir / "table.out").string(), &table),
            0);
  EXPECT_NE(table.find("pelvis: SlimeVR BMI270 ESP8266 firmware 0.6.0-sim " + mac +
                       ", battery 80 %, 3.70 V, signal -60 dBm, 31.5 C"),
            std::string::npos)
      << table;

  // The board stops: its sensors go stale (no repeats of a silent board's orientation), then
  // after the 3 s without a word show disconnected, last battery kept.
  kill(sim, SIGTERM);
  EXPECT_EQ(test::wait_exit(sim), 0);
  bool stale = false, gone = false;
  for (int i = 0; i < 100 && !gone; ++i) {
    std::this_thread::sleep_for(100ms);
    st = status_json(sock, dir);
    const auto* a = sensor(st, "pelvis");
    stale = stale || (a && (*a)["state"] == "stale");
    gone = a && (*a)["state"] == "disconnected";
  }
  EXPECT_TRUE(stale);
  EXPECT_TRUE(gone) << st.dump();
  if (const auto* a = sensor(st, "pelvis")) {
    EXPECT_DOUBLE_EQ((*a)["battery_pct"].get<double>(), 80);
  }
  kill(d, SIGTERM);
  EXPECT_EQ(test::wait_exit(d), 0) << test::slurp_file((dir / "mocapd.log.err").string());
  fs::remove_all(dir);
}
