// End to end over real UDP: SlimeVR tracker boards (two `mocap simulate --protocol slimevr`
// processes and one in-process board) connect to the real mocapd through the handshake, their
// orientations drive segments on the JSON pose stream, a tracker's reset button calibrates, and
// a recording replays from the raw datagrams through the decoder, identically twice.
#include <gtest/gtest.h>

#include <filesystem>

#include "../common/e2e_process.hpp"
#include "../common/free_port.hpp"
#include "mocap/daemon/control.hpp"
#include "mocap/devsim/sim_slimevr.hpp"
#include "mocap/session/session_reader.hpp"

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using namespace mocap::test;

namespace {

nlohmann::json status(const std::string& sock) {
  try {
    return nlohmann::json::parse(mocap::daemon::control_call(sock, "status"));
  } catch (const std::exception&) {
    return {};
  }
}

}  // namespace

TEST(SlimeVrMocapd, TrackersConnectStreamCalibrateByButtonRecordAndReplay) {
  const fs::path dir = fs::temp_directory_path() / ("mocap-e2e-slime-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string sock = (dir / "ctl.sock").string();
  const int udp = free_loopback_port(SOCK_DGRAM);
  const int json = free_loopback_port(SOCK_STREAM);
  const std::string server = "127.0.0.1:" + std::to_string(udp);
  // Five rig sensors on three boards; board 3's sensor 1 is not in the rig (ignored).
  const struct {
    const char* name;
    const char* mac;
    int tracker;
  } rig[] = {{"pelvis", "02:5E:00:00:00:01", 0},
             {"thigh_l", "02:5E:00:00:00:01", 1},
             {"shank_l", "02:5E:00:00:00:02", 0},
             {"thigh_r", "02:5E:00:00:00:02", 1},
             {"shank_r", "02:5E:00:00:00:03", 0}};
  std::ofstream cfg(dir / "rig.toml");
  cfg << "[filter]\nuse_mag = false\n[calibration]\ncountdown_s = 0.5\ncapture_s = 0.5\n"
      << "[recording]\ndirectory = \"" << dir.string() << "\"\n";
  for (const auto& s : rig)
    cfg << "[[sensor]]\nname = \"" << s.name << "\"\ndriver = \"slimevr\"\nport = \"udp:" << server
        << "\"\nsegment = \"" << s.name << "\"\noptions = { mac = \"" << s.mac
        << "\", tracker = " << s.tracker << " }\n";
  cfg.close();
  const pid_t d =
      spawn({kBinDir + "mocapd", "--config", (dir / "rig.toml").string(), "--set",
             "daemon.control_socket=" + sock, "--set", "outputs.json.port=" + std::to_string(json),
             "--set", "outputs.posture.shm_name=/mocap-e2e-slime-" + std::to_string(getpid()),
             "--log-level", "info"},
            (dir / "mocapd.log").string());
  ASSERT_GT(d, 0);
  std::vector<pid_t> sims;
  for (const char* mac : {"02:5E:00:00:00:01", "02:5E:00:00:00:02"})
    sims.push_back(spawn({kBinDir + "mocap", "simulate", "--protocol", "slimevr", "--udp", server,
                          "--option", std::string("mac=") + mac, "--option", "sensors=2",
                          "--motion", "static", "--duration", "60"},
                         (dir / (std::string("sim-") + mac[16] + ".log")).string()));
  mocap::SimSlimeOptions o;
  o.server = server;
  o.mac = "02:5E:00:00:00:03";
  o.sensors = 2;
  o.motion = "static";  // a calibration needs everyone still
  mocap::SimSlimeTracker board3(o);
  board3.start();

  // Every sensor streams through the handshake the daemon answered. (Board 3 is asked to be
  // connected in the same look: on a loaded machine a board that missed the server for 3 s
  // handshakes again, and is back within a second.)
  nlohmann::json st;
  bool streaming = false;
  for (int i = 0; i < 150 && !streaming; ++i) {
    std::this_thread::sleep_for(100ms);
    st = status(sock);
    if (!st.is_object() || !st.contains("sensors")) continue;
    streaming = board3.connected();
    for (const auto& s : st["sensors"])
      streaming = streaming && s["state"] == "streaming";
  }
  ASSERT_TRUE(streaming) << board3.connected() << st.dump()
                         << slurp_file((dir / "mocapd.log.err").string());
  EXPECT_FALSE(st["calibrated"].get<bool>());

  // The tracker's reset button (packet 21, full reset) runs the calibration.
  board3.press(mocap::slimevr::kResetFull);
  bool calibrated = false;
  for (int i = 0; i < 100 && !calibrated; ++i) {
    std::this_thread::sleep_for(100ms);
    st = status(sock);
    calibrated = st.is_object() && st.value("calibrated", false);
  }
  EXPECT_TRUE(calibrated) << st.dump();
  EXPECT_NE(
      slurp_file((dir / "mocapd.log.err").string()).find("asked for a full (calibration) reset"),
      std::string::npos);

  // Board 3 restarts (a new socket, as after a power cycle) turning: it handshakes again and
  // its segment follows it, while the boards at rest keep theirs still.
  board3.stop();
  o.motion = "rotate";
  mocap::SimSlimeTracker board3b(o);
  board3b.start();
  for (int i = 0; i < 100 && !board3b.connected(); ++i)
    std::this_thread::sleep_for(50ms);
  ASSERT_TRUE(board3b.connected());
  std::this_thread::sleep_for(300ms);

  // Pose frames: the rig's five segments tracked, unit quaternions, only shank_r moving.
  auto lines = read_json_lines(static_cast<uint16_t>(json), 60);
  ASSERT_EQ(lines.size(), 60u);
  std::map<std::string, std::pair<nlohmann::json, nlohmann::json>> first_last;
  for (const auto& seg : lines.front()["segments"])
    first_last[seg["name"]].first = seg;
  for (const auto& seg : lines.back()["segments"])
    first_last[seg["name"]].second = seg;
  const auto angle = [](const nlohmann::json& a, const nlohmann::json& b) {
    double dot = 0;
    for (int k = 0; k < 4; ++k)
      dot += a["q"][k].get<double>() * b["q"][k].get<double>();
    return 2 * std::acos(std::min(1.0, std::abs(dot)));
  };
  for (const auto& s : rig) {
    const auto& [a, b] = first_last[s.name];
    EXPECT_EQ(b["flags"].get<int>() & 1, 1) << s.name << " tracked";
    double n = 0;
    for (const auto& c : b["q"])
      n += c.get<double>() * c.get<double>();
    EXPECT_NEAR(n, 1.0, 1e-3);
    if (std::string(s.mac) == "02:5E:00:00:00:03")
      EXPECT_GT(angle(a, b), 0.05) << s.name << " follows its turning tracker";
    else
      EXPECT_LT(angle(a, b), 1e-3) << s.name << " at rest";
  }

  // Record, then replay from the raw datagrams (through the decoder) twice: identical poses.
  std::string out;
  EXPECT_EQ(run_program({kBinDir + "mocapctl", "--socket", sock, "record", "start", "s.mcap"},
                        (dir / "ctl.out").string(), &out),
            0)
      << out;
  std::this_thread::sleep_for(1500ms);
  EXPECT_EQ(run_program({kBinDir + "mocapctl", "--socket", sock, "record", "stop"},
                        (dir / "ctl.out").string(), &out),
            0)
      << out;
  board3b.stop();
  for (pid_t p : sims)
    kill(p, SIGTERM);
  for (pid_t p : sims)
    EXPECT_EQ(wait_exit(p), 0);
  kill(d, SIGTERM);
  EXPECT_EQ(wait_exit(d), 0) << slurp_file((dir / "mocapd.log.err").string());

  mocap::SessionReader r;
  std::string err;
  ASSERT_TRUE(r.open((dir / "s.mcap").string(), &err)) << err;
  mocap::SessionReader::Block b;
  int raw = 0;
  while (r.next(b))
    raw += b.type == mocap::session::BlockType::raw;
  EXPECT_GT(raw, 100);
  std::string poses[2];
  for (int k = 0; k < 2; ++k) {
    const std::string p = (dir / ("raw" + std::to_string(k) + ".csv")).string();
    ASSERT_EQ(run_program({kBinDir + "mocap", "replay", (dir / "s.mcap").string(), "--source",
                           "raw", "--poses", p, "--quiet"},
                          (dir / "replay.out").string(), &out),
              0)
        << out;
    poses[k] = slurp_file(p);
  }
  EXPECT_GT(poses[0].size(), 10000u);
  EXPECT_EQ(poses[0], poses[1]);
  EXPECT_EQ(poses[0].find("nan"), std::string::npos);
  fs::remove_all(dir);
}

// `mocap devices` lists a tracker that is saying hello (not yet answered) with its rig snippet.
TEST(SlimeVrMocapd, DevicesListsTrackersThatSayHello) {
  const int udp = free_loopback_port(SOCK_DGRAM);
  mocap::SimSlimeOptions o;
  o.server = "127.0.0.1:" + std::to_string(udp);
  o.mac = "02:5E:00:00:AB:CD";
  mocap::SimSlimeTracker board(o);
  const fs::path out_file =
      fs::temp_directory_path() / ("mocap-e2e-slime-devices-" + std::to_string(getpid()));
  const pid_t p = spawn({kBinDir + "mocap", "devices", "--slimevr-port", std::to_string(udp),
                         "--slimevr-listen", "2.5"},
                        out_file.string());
  std::this_thread::sleep_for(300ms);  // the listener binds first
  board.start();
  EXPECT_EQ(wait_exit(p), 0);
  board.stop();
  const std::string out = slurp_file(out_file.string());
  EXPECT_NE(out.find("tracker 02:5E:00:00:AB:CD at 127.0.0.1"), std::string::npos) << out;
  EXPECT_NE(out.find("firmware \"0.6.0-sim\", protocol 22"), std::string::npos) << out;
  EXPECT_NE(out.find("options = { mac = \"02:5E:00:00:AB:CD\", tracker = 0 }"), std::string::npos)
      << out;
  EXPECT_FALSE(board.connected());  // listening answers nothing
  fs::remove(out_file);
  fs::remove(out_file.string() + ".err");
}
