// The Blender live link (blender/mocap_live, issue 30 part 1) in Debian's Blender, headless,
// against the real `mocapd --demo`: tests/blender/live_link_check.py installs the add-on from
// the zip CMake built, connects it to the pose stream, and reports what it measured; this test
// starts mocapd (a free port, its own runtime directory, a take recorded from the start),
// restarts it when the script makes it quit (as systemd would), and checks the figures: bones
// within 0.1 deg of the frames the script read itself, retargeted Mixamo and Rigify armatures, 2 s
// recorded into an Action with every frame of the span, a reconnect after the restart, and the
// imported take's bone rotations against the session file read here with SessionReader.
#include <gtest/gtest.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/wait.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "../common/blender_runner.hpp"
#include "../common/e2e_process.hpp"
#include "../common/free_port.hpp"
#include "../common/raw_unix_call.hpp"
#include "../common/temp_dir.hpp"
#include "mocap/session/session_reader.hpp"

namespace mocap {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

/// Ours (x fwd, y left, z up) to Blender's axes (character facing -Y): A q A^-1 with A = -90
/// deg about z, i.e. (w, x, y, z) -> (w, y, -x, z). Written out here as in the script.
Eigen::Quaterniond blender_from_ours(const std::array<float, 4>& q) {
  return Eigen::Quaterniond(q[0], q[2], -q[1], q[3]).normalized();
}

double angle_deg(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return 2.0 * std::acos(std::min(1.0, std::abs(a.dot(b)))) * 180.0 / M_PI;
}

bool control_answers(const std::string& socket) {
  return test::raw_unix_call(socket, "status\n").find("\"ok\":true") != std::string::npos;
}

}  // namespace

TEST(BlenderLiveLink, FollowsTheStreamRecordsReconnectsAndImportsATake) {
  if (!test::have_blender()) GTEST_SKIP() << "blender not installed";
  const std::string zip = std::string(MOCAP_BINARY_DIR) + "/blender/mocap_live.zip";
  ASSERT_TRUE(fs::exists(zip)) << zip << " (the blender_addon target)";
  test::TempDir dir("blender");
  const int port = test::free_loopback_port(SOCK_STREAM);
  const std::string control = dir.file("ctl.sock"), take = dir.file("take.mocapses");
  {
    std::ofstream cfg(dir.file("rig.toml"));
    cfg << "[daemon]\ncontrol_socket = \"" << control << "\"\n"
        << "[outputs.json]\nenabled = true\nport = " << port << "\n"
        << "[outputs.posture]\nenabled = false\n"
        << "[recording]\ndirectory = \"" << dir.path() << "\"\nauto_start = \"take.mocapses\"\n"
        << "[demo]\npath = \"direct\"\n";  // the performer's samples straight in: a light demo
  }
  const std::vector<std::string> mocapd = {test::kBinDir + "mocapd", "--config",
                                           dir.file("rig.toml"), "--demo"};
  pid_t daemon = test::spawn(mocapd, dir.file("mocapd.log"));
  ASSERT_GT(daemon, 0);
  for (int i = 0; i < 1500 && !control_answers(control); ++i)
    std::this_thread::sleep_for(10ms);
  ASSERT_TRUE(control_answers(control)) << test::slurp_file(dir.file("mocapd.log.err"));

  // Blender installs the add-on into its own user directories here, not the user's.
  ::setenv("BLENDER_USER_SCRIPTS", dir.file("blender-scripts").c_str(), 1);
  ::setenv("BLENDER_USER_CONFIG", dir.file("blender-config").c_str(), 1);
  const std::string result = dir.file("result.json"), log = dir.file("blender.log");
  const pid_t blender =
      test::spawn(test::blender_argv(
                      std::string(MOCAP_SOURCE_DIR) + "/tests/blender/live_link_check.py",
                      {std::to_string(port), control, take, test::kBinDir + "mocap", zip, result}),
                  log);
  ASSERT_GT(blender, 0);
  // Supervise: when the script has made mocapd quit, start it again (once), as systemd would.
  int blender_status = -1, restarts = 0, first_exit = -1;
  const auto deadline = std::chrono::steady_clock::now() + 150s;
  while (std::chrono::steady_clock::now() < deadline) {
    int st = 0;
    if (::waitpid(blender, &st, WNOHANG) == blender) {
      blender_status = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
      break;
    }
    if (daemon > 0 && ::waitpid(daemon, &st, WNOHANG) == daemon) {
      first_exit = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
      daemon = restarts++ == 0 ? test::spawn(mocapd, dir.file("mocapd2.log")) : -1;
    }
    std::this_thread::sleep_for(20ms);
  }
  if (blender_status < 0) {
    ::kill(blender, SIGKILL);
    ::waitpid(blender, nullptr, 0);
  }
  if (daemon > 0) {
    ::kill(daemon, SIGTERM);
    EXPECT_EQ(test::wait_exit(daemon, 30), 0);
  }
  const std::string blender_log = test::slurp_file(log) + test::slurp_file(log + ".err");
  ASSERT_EQ(blender_status, 0) << blender_log;
  EXPECT_EQ(restarts, 1);
  EXPECT_EQ(first_exit, 0) << test::slurp_file(dir.file("mocapd.log.err"));
  std::ifstream in(result);
  ASSERT_TRUE(in) << blender_log;
  const auto r = nlohmann::json::parse(in);

  // Live: every bone of our armature on the frame it shows, against the script's own reader.
  const auto& live = r["live"];
  EXPECT_GE(live["frames_checked"].get<int>(), 60);
  EXPECT_LT(live["max_err_deg"].get<double>(), 0.1);
  EXPECT_LT(live["max_pos_err_m"].get<double>(), 1e-3);
  EXPECT_GT(live["max_motion_deg"].get<double>(), 5.0);  // the performer moved meanwhile
  // Retarget: a Mixamo-named T-pose armature and Rigify's meta-rig, found by their names,
  // every bone along its segment.
  EXPECT_EQ(r["retarget"]["preset"], "MOCAP");  // our bone names are Mixamo's, less the prefix
  EXPECT_EQ(r["rigify"]["preset"], "RIGIFY");
  for (const char* rig : {"retarget", "rigify"}) {
    EXPECT_EQ(r[rig]["mapped"], 16) << rig;
    EXPECT_GE(r[rig]["frames_checked"].get<int>(), 20) << rig;
    EXPECT_LT(r[rig]["max_dir_err_deg"].get<double>(), 0.1) << rig;
  }
  // Record: 2 s, every frame of the stream in that span keyed once, at its own time.
  const auto& rec = r["record"];
  EXPECT_TRUE(rec["contiguous"].get<bool>());
  EXPECT_EQ(rec["frames"], rec["stream_frames_in_span"]);
  EXPECT_EQ(rec["keys"], rec["frames"]);
  EXPECT_GE(rec["frames"].get<int>(), 150);  // the demo publishes 95-120 frames/s
  EXPECT_NEAR(rec["duration_s"].get<double>(), 2.0, 0.25);
  EXPECT_LT(rec["key_time_err_s"].get<double>(), 1e-4);
  EXPECT_EQ(rec["t_unix_ns"], rec["first_t_unix_ns"]);
  EXPECT_EQ(rec["fcurves"], 16 * 4 + 3);  // 16 rotations and the root's location
  // Restart: the add-on said mocapd was gone, came back by itself, and follows the new daemon.
  const auto& rs = r["restart"];
  EXPECT_NE(rs["waiting_message"].get<std::string>().find("reconnecting"), std::string::npos)
      << rs["waiting_message"];
  EXPECT_GE(rs["connections"].get<int>(), 2);
  EXPECT_GE(rs["frames_checked"].get<int>(), 20);
  EXPECT_LT(rs["max_err_deg"].get<double>(), 0.1);
  // Import: the first daemon's take, every pose keyed; rotations against the file itself.
  SessionReader reader;
  std::string error;
  ASSERT_TRUE(reader.open(take, &error)) << error;
  std::vector<PoseFrame> poses;
  SessionReader::Block b;
  while (reader.next(b))
    if (b.type == session::BlockType::pose) poses.push_back(b.pose);
  const auto& imp = r["import"];
  ASSERT_GT(poses.size(), 100u);
  EXPECT_EQ(imp["frames"].get<std::size_t>(), poses.size());
  EXPECT_EQ(imp["keys"].get<std::size_t>(), poses.size());
  EXPECT_EQ(imp["first_frame"].get<uint64_t>(), poses.front().frame);
  EXPECT_EQ(imp["last_frame"].get<uint64_t>(), poses.back().frame);
  EXPECT_EQ(
      std::stoll(imp["t_unix_ns"].get<std::string>()),
      poses.front().t_ns + (reader.header().t_start_unix_ns - reader.header().t_start_host_ns));
  double worst = 0;
  for (const auto& s : imp["samples"]) {
    const PoseFrame& f = poses.at(s["key"].get<std::size_t>());
    for (int seg = 0; seg < kSegmentCount; ++seg) {
      const auto& q = s["bones"][seg];
      const Eigen::Quaterniond got(q[0].get<double>(), q[1].get<double>(), q[2].get<double>(),
                                   q[3].get<double>());
      worst = std::max(worst, angle_deg(got, blender_from_ours(f.q_earth_segment[seg])));
    }
  }
  EXPECT_LT(worst, 0.1);
  EXPECT_TRUE(r["disabled"].get<bool>());
  std::printf(
      "[figures] live: %d frames, worst %.4f deg (%s), %.2g m (performer moved %.0f deg); Mixamo "
      "retarget worst %.4f deg, Rigify %.4f deg; record: %d frames in %.3f s; after restart %d "
      "frames, worst "
      "%.4f deg; import: %zu poses in %.2f s, worst %.4f deg at %zu keys\n",
      live["frames_checked"].get<int>(), live["max_err_deg"].get<double>(),
      live["worst_bone"].get<std::string>().c_str(), live["max_pos_err_m"].get<double>(),
      live["max_motion_deg"].get<double>(), r["retarget"]["max_dir_err_deg"].get<double>(),
      r["rigify"]["max_dir_err_deg"].get<double>(), rec["frames"].get<int>(),
      rec["duration_s"].get<double>(), rs["frames_checked"].get<int>(),
      rs["max_err_deg"].get<double>(), poses.size(), imp["seconds"].get<double>(), worst,
      imp["samples"].size());
}

TEST(BlenderLiveLink, TheStreamModuleKeepsFramesRefusesBadLinesAndKeepsTimesInOrder) {
  test::TempDir dir("blender");
  const std::string out = dir.file("units.out");
  const int rc = test::run_program(
      {"/usr/bin/python3", std::string(MOCAP_SOURCE_DIR) + "/tests/blender/stream_units.py",
       std::string(MOCAP_SOURCE_DIR) + "/blender/mocap_live/stream.py"},
      out);
  const std::string text = test::slurp_file(out) + test::slurp_file(out + ".err");
  EXPECT_EQ(rc, 0) << text;
  EXPECT_EQ(text, "ok\n");
}

TEST(BlenderLiveLink, TheStreamClientWaitsForMocapdThenReadsItsPrivateUnixSocket) {
  test::TempDir dir("blender");
  const std::string sock = dir.file("pose.sock"), out = dir.file("client.out");
  const pid_t client = test::spawn(
      {"/usr/bin/python3", std::string(MOCAP_SOURCE_DIR) + "/tests/blender/stream_check.py",
       std::string(MOCAP_SOURCE_DIR) + "/blender/mocap_live/stream.py", sock},
      out);
  ASSERT_GT(client, 0);
  for (int i = 0; i < 1000 && test::slurp_file(out).find("waiting") == std::string::npos; ++i)
    std::this_thread::sleep_for(10ms);
  {
    std::ofstream cfg(dir.file("rig.toml"));
    cfg << "[daemon]\ncontrol_socket = \"" << dir.file("ctl.sock") << "\"\n"
        << "[outputs.json]\nenabled = true\nunix_socket = \"" << sock << "\"\n"
        << "[outputs.posture]\nenabled = false\n[demo]\npath = \"direct\"\n";
  }
  const pid_t daemon =
      test::spawn({test::kBinDir + "mocapd", "--config", dir.file("rig.toml"), "--demo"},
                  dir.file("mocapd.log"));
  ASSERT_GT(daemon, 0);
  const int client_status = test::wait_exit(client, 60);
  ::kill(daemon, SIGTERM);
  EXPECT_EQ(test::wait_exit(daemon, 30), 0);
  const std::string text = test::slurp_file(out) + test::slurp_file(out + ".err");
  EXPECT_EQ(client_status, 0) << text;
  // Before mocapd: waiting, with the reason (no socket there yet); then connected once.
  EXPECT_NE(text.find("waiting: no mocapd at " + sock + " ("), std::string::npos) << text;
  EXPECT_NE(text.find("ok connections=1 frames="), std::string::npos) << text;
  EXPECT_NE(text.find(" bad_lines=0 state=stopped"), std::string::npos) << text;
}

}  // namespace mocap
