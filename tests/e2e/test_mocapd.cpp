// End to end: the real mocapd binary with --demo (virtual performer -> witmotion bytes -> ptys
// -> real drivers -> pipeline), driven by the real mocapctl, read by a TCP client; a recording
// made over the control socket replays bit-identically with `mocap replay`; SIGTERM while
// recording exits cleanly with a readable session; VRChat OSC trackers reach oscdump.
#include <arpa/inet.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "../common/e2e_process.hpp"
#include "../common/free_port.hpp"
#include "mocap/daemon/control.hpp"
#include "mocap/session/session_reader.hpp"
#include "mocap/skeleton/body_model.hpp"

extern char** environ;
namespace fs = std::filesystem;
using namespace std::chrono_literals;

namespace {

const std::string kBin = mocap::test::kBinDir;
using mocap::test::read_json_lines;
using mocap::test::slurp_file;
using mocap::test::spawn;
using mocap::test::wait_exit;

int run(const std::vector<std::string>& argv, std::string* out = nullptr) {
  const std::string f =
      (fs::temp_directory_path() / ("mocap-e2e-out-" + std::to_string(getpid()))).string();
  const int rc = wait_exit(spawn(argv, f), 120);
  if (out) {
    std::ifstream in(f);
    std::stringstream ss;
    ss << in.rdbuf();
    *out = ss.str();
  }
  return rc;
}

/// The daemon's newest frame number (status), -1 when it does not answer.
int64_t frame_number(const std::string& sock) {
  try {
    return nlohmann::json::parse(mocap::daemon::control_call(sock, "status"))["frame"]
        .get<int64_t>();
  } catch (const std::exception&) {
    return -1;
  }
}

/// Waits until the daemon has published `frames` more frames (at most 30 s): a recording's
/// length in frames, not in wall time (a loaded machine publishes fewer per second).
void wait_frames(const std::string& sock, int64_t frames) {
  const int64_t from = frame_number(sock);
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (frame_number(sock) < from + frames && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(50ms);
}

uint16_t free_port() {
  return static_cast<uint16_t>(mocap::test::free_loopback_port(SOCK_STREAM));
}

}  // namespace

TEST(Mocapd, DemoControlStreamRecordReplay) {
  const fs::path dir = fs::temp_directory_path() / ("mocap-e2e-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string sock = (dir / "ctl.sock").string();
  const uint16_t port = free_port();
  const pid_t d = spawn({kBin + "mocapd", "--demo", "--set", "daemon.control_socket=" + sock,
                         "--set", "outputs.json.port=" + std::to_string(port), "--set",
                         "outputs.posture.shm_name=/mocap-e2e-" + std::to_string(getpid()), "--set",
                         "recording.directory=" + dir.string(), "--log-level", "warn"},
                        (dir / "mocapd.log").string());
  // Wait until it answers.
  nlohmann::json st;
  for (int i = 0; i < 100; ++i) {
    try {
      st = nlohmann::json::parse(mocap::daemon::control_call(sock, "status"));
      if (st["samples"].get<uint64_t>() > 500) break;
    } catch (const std::exception&) {
    }
    std::this_thread::sleep_for(100ms);
  }
  ASSERT_TRUE(st.is_object()) << slurp_file((dir / "mocapd.log.err").string());
  ASSERT_EQ(st["sensors"].size(), 15u);
  for (const auto& s : st["sensors"])
    EXPECT_EQ(s["state"], "streaming") << s.dump();
  EXPECT_TRUE(st["demo"].get<bool>());

  // The pose stream: frames increase, quaternions are unit, sensors listed.
  auto lines = read_json_lines(port, 20);
  ASSERT_EQ(lines.size(), 20u);
  for (size_t i = 1; i < lines.size(); ++i)
    EXPECT_GT(lines[i]["frame"], lines[i - 1]["frame"]);
  // Wall clock beside the monotonic time: t_unix_ns - t_ns is realtime - monotonic (sampled by
  // the pipeline), and the frames are from just now.
  {
    timespec rt{}, mt{};
    clock_gettime(CLOCK_REALTIME, &rt);
    clock_gettime(CLOCK_MONOTONIC, &mt);
    const int64_t offset_now =
        (rt.tv_sec - mt.tv_sec) * 1'000'000'000ll + (rt.tv_nsec - mt.tv_nsec);
    const int64_t now_unix = rt.tv_sec * 1'000'000'000ll + rt.tv_nsec;
    for (const auto& l : lines) {
      const int64_t t_ns = l["t_ns"].get<int64_t>(), t_unix_ns = l["t_unix_ns"].get<int64_t>();
      EXPECT_NEAR(static_cast<double>(t_unix_ns - t_ns), static_cast<double>(offset_now), 5e6);
      EXPECT_LT(now_unix - t_unix_ns, 5'000'000'000ll);
      EXPECT_GE(now_unix - t_unix_ns, 0);
    }
  }
  for (const auto& seg : lines.back()["segments"]) {
    double n = 0;
    for (const auto& c : seg["q"])
      n += c.get<double>() * c.get<double>();
    EXPECT_NEAR(n, 1.0, 1e-3);
  }
  EXPECT_EQ(lines.back()["sensors"].size(), 15u);

  // mocapctl: human table, a malformed request is refused, the daemon survives it.
  std::string out;
  EXPECT_EQ(run({kBin + "mocapctl", "--socket", sock, "status"}, &out), 0);
  EXPECT_NE(out.find("foot_r"), std::string::npos) << out;
  EXPECT_EQ(run({kBin + "mocapctl", "--socket", sock, "calibrate", "apose"}), 2);
  // No pose named: the configured calibration.pose (npose by default).
  EXPECT_EQ(run({kBin + "mocapctl", "--socket", sock, "calibrate"}, &out), 0);
  EXPECT_NE(out.find("calibration (npose)"), std::string::npos) << out;
  // status --json: where the streams and the control socket are, numbers at their precision.
  EXPECT_EQ(run({kBin + "mocapctl", "--socket", sock, "status", "--json"}, &out), 0);
  const auto js = nlohmann::json::parse(out);
  EXPECT_EQ(js["streams"]["json"]["port"], port);
  EXPECT_TRUE(js["streams"]["json"]["enabled"].get<bool>());
  EXPECT_EQ(js["streams"]["vmc"]["port"], 39539);
  EXPECT_EQ(js["streams"]["vrchat"]["port"], 9000);
  EXPECT_EQ(js["streams"]["control_socket"], sock);
  EXPECT_FALSE(std::regex_search(out, std::regex("[0-9]\\.[0-9]{7,}"))) << out;
  auto bad = nlohmann::json::parse(mocap::daemon::control_call(sock, std::string(9000, 'z')));
  EXPECT_FALSE(bad["ok"].get<bool>());

  // Record 150 frames (1.5 s at the demo's rate), stop, record again and stop with SIGTERM after
  // 70 frames.
  EXPECT_EQ(run({kBin + "mocapctl", "--socket", sock, "record", "start", "a.mocapses"}), 0);
  wait_frames(sock, 150);
  EXPECT_EQ(run({kBin + "mocapctl", "--socket", sock, "record", "stop"}), 0);
  EXPECT_EQ(run({kBin + "mocapctl", "--socket", sock, "record", "start", "b.mocapses"}), 0);
  wait_frames(sock, 70);
  kill(d, SIGTERM);
  EXPECT_EQ(wait_exit(d), 0) << slurp_file((dir / "mocapd.log.err").string());
  EXPECT_FALSE(fs::exists(sock));

  for (const char* f : {"a.mocapses", "b.mocapses"}) {
    mocap::SessionReader r;
    std::string err;
    ASSERT_TRUE(r.open((dir / f).string(), &err)) << err;
    EXPECT_EQ(r.header().sensors.size(), 15u);
    mocap::SessionReader::Block b;
    int raw = 0, samples = 0, poses = 0;
    while (r.next(b)) {
      raw += b.type == mocap::session::BlockType::raw;
      samples += b.type == mocap::session::BlockType::sample;
      poses += b.type == mocap::session::BlockType::pose;
    }
    EXPECT_EQ(r.end(), mocap::SessionReader::End::clean) << f;
    // Counts, not rates: how many reads the bytes arrive in depends on scheduling (a loaded
    // machine reads bigger chunks), so raw blocks are only required to be there.
    EXPECT_GT(raw, 0) << f;
    EXPECT_GT(samples, 300) << f;
    EXPECT_GT(poses, 30) << f;
  }

  // Offline replay is deterministic, from samples and from raw bytes through the decoders, and
  // the same with every filter on the replay's thread (--filter-threads 0) as with filters on
  // other threads (the default).
  for (const char* source : {"samples", "raw"}) {
    const std::string p1 = (dir / (std::string(source) + "1.csv")).string();
    const std::string p2 = (dir / (std::string(source) + "2.csv")).string();
    // --poses: the deprecated spelling of --csv, still accepted.
    ASSERT_EQ(run({kBin + "mocap", "replay", (dir / "a.mocapses").string(), "--source", source,
                   "--poses", p1, "--quiet", "--filter-threads", "0"},
                  &out),
              0)
        << out;
    ASSERT_EQ(run({kBin + "mocap", "replay", (dir / "a.mocapses").string(), "--source", source,
                   "--csv", p2, "--bvh", (dir / "a.bvh").string(), "--quiet"}),
              0);
    const std::string a = slurp_file(p1), b = slurp_file(p2);
    EXPECT_GT(a.size(), 10000u);
    EXPECT_EQ(a, b) << source;
    EXPECT_EQ(a.find("nan"), std::string::npos);
  }
  EXPECT_NE(slurp_file((dir / "a.bvh").string()).find("HIERARCHY"), std::string::npos);
  fs::remove_all(dir);
}

TEST(Mocapd, RefusesBadConfigWithPosition) {
  const fs::path f =
      fs::temp_directory_path() / ("mocap-e2e-bad-" + std::to_string(getpid()) + ".toml");
  std::ofstream(f) << "[outputs.json]\nprot = 1\n";
  std::string out;
  EXPECT_EQ(run({kBin + "mocapd", "--config", f.string()}, &out), 1);
  const std::string err = slurp_file(fs::temp_directory_path() /
                                     ("mocap-e2e-out-" + std::to_string(getpid()) + ".err"));
  EXPECT_NE(err.find(f.string() + ":2:8: outputs.json.prot: unknown key (did you mean 'port'?)"),
            std::string::npos)
      << err;
  EXPECT_EQ(run({kBin + "mocapd", "--print-config", "--set", "outputs.json.port=7555"}, &out), 0);
  EXPECT_NE(out.find("port = 7555"), std::string::npos) << out;
  fs::remove(f);
}

// Issue 22 item 7: a WitMotion rig asking 100 Hz at 9600 baud passes the check with a warning
// naming the sensor, the link and the samples/s it carries.
TEST(Mocapd, CheckConfigWarnsWhenTheRateExceedsTheBaud) {
  const fs::path f =
      fs::temp_directory_path() / ("mocap-e2e-baud-" + std::to_string(getpid()) + ".toml");
  std::ofstream(f) << "[[sensor]]\nname = \"hips\"\ndriver = \"witmotion\"\n"
                      "port = \"/dev/ttyUSB0\"\nrate_hz = 100\nsegment = \"pelvis\"\n";
  std::string out;
  EXPECT_EQ(run({kBin + "mocapd", "--check-config", f.string()}, &out), 0);
  const std::string err = slurp_file(fs::temp_directory_path() /
                                     ("mocap-e2e-out-" + std::to_string(getpid()) + ".err"));
  EXPECT_NE(err.find("warning: sensor[0] (hips): witmotion at 100 Hz"), std::string::npos) << err;
  EXPECT_NE(err.find("9600 baud carries 9600: at most 14 samples/s"), std::string::npos) << err;
  fs::remove(f);
}

// Golden: recorded sessions under tests/data/ replay to their stored expected poses (numeric
// tolerance: 1e-4 on quaternion components, 1e-3 m on positions). After an intended change,
// regenerate with scripts/regen-golden. The session extension is `.mocapses`; the golden
// session keeps its older `.mcap` name on purpose: files are identified by their magic, so it
// also checks that sessions recorded before the rename still replay.
TEST(Golden, RecordedSessionsReplayToExpectedPoses) {
  int checked = 0;
  for (const auto& e : fs::directory_iterator(fs::path(MOCAP_SOURCE_DIR) / "tests/data")) {
    if (e.path().extension() != ".mocapses" && e.path().extension() != ".mcap") continue;
    fs::path expected = e.path();
    expected.replace_extension(".expected.csv");
    ASSERT_TRUE(fs::exists(expected)) << expected;
    const std::string got_path =
        (fs::temp_directory_path() / ("mocap-golden-" + std::to_string(getpid()) + ".csv"))
            .string();
    ASSERT_EQ(run({kBin + "mocap", "replay", e.path().string(), "--csv", got_path, "--quiet"}), 0);
    std::ifstream want(expected), got(got_path);
    std::string lw, lg;
    int line = 0;
    double worst_q = 0, worst_p = 0;
    while (std::getline(want, lw)) {
      ++line;
      ASSERT_TRUE(std::getline(got, lg)) << "replay has fewer lines than " << expected;
      if (line == 1) {
        EXPECT_EQ(lw, lg);
        continue;
      }
      std::vector<std::string> a, b;
      std::stringstream sa(lw), sb(lg);
      std::string cell;
      while (std::getline(sa, cell, ','))
        a.push_back(cell);
      while (std::getline(sb, cell, ','))
        b.push_back(cell);
      ASSERT_EQ(a.size(), 9u);
      ASSERT_EQ(b.size(), 9u);
      EXPECT_EQ(a[1], b[1]) << "line " << line;
      EXPECT_NEAR(std::stod(a[0]), std::stod(b[0]), 1e-6) << "line " << line;
      for (int k = 2; k < 6; ++k)
        worst_q = std::max(worst_q, std::abs(std::stod(a[k]) - std::stod(b[k])));
      for (int k = 6; k < 9; ++k)
        worst_p = std::max(worst_p, std::abs(std::stod(a[k]) - std::stod(b[k])));
    }
    EXPECT_FALSE(std::getline(got, lg)) << "replay has more lines than " << expected;
    EXPECT_LE(worst_q, 1e-4) << e.path();
    EXPECT_LE(worst_p, 1e-3) << e.path();
    EXPECT_GT(line, 100);
    fs::remove(got_path);
    ++checked;
  }
  EXPECT_GE(checked, 1);
}

// The demo calibrates itself during the performer's N-pose stand (as `mocapctl calibrate npose`
// would), after which the streamed avatar stands upright: head above pelvis, feet below it near
// the floor, pelvis upright.
TEST(Mocapd, DemoCalibratesItselfAndStandsUpright) {
  const fs::path dir = fs::temp_directory_path() / ("mocap-e2e-cal-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string sock = (dir / "ctl.sock").string();
  const uint16_t port = free_port();
  const pid_t d = spawn({kBin + "mocapd", "--demo", "--set", "daemon.control_socket=" + sock,
                         "--set", "outputs.json.port=" + std::to_string(port), "--set",
                         "outputs.posture.shm_name=/mocap-e2e-cal-" + std::to_string(getpid()),
                         "--log-level", "info"},
                        (dir / "mocapd.log").string());
  // A failed assertion returns early: the daemon must not outlive the test.
  struct KillOnExit {
    pid_t pid;
    ~KillOnExit() {
      if (pid > 0 && kill(pid, SIGKILL) == 0) waitpid(pid, nullptr, 0);
    }
  } guard{d};
  nlohmann::json st;
  bool calibrated = false;
  for (int i = 0; i < 300 && !calibrated; ++i) {
    std::this_thread::sleep_for(100ms);
    std::string out;
    if (run({kBin + "mocapctl", "--socket", sock, "status", "--json"}, &out) != 0) continue;
    try {
      st = nlohmann::json::parse(out);
      calibrated = st["calibrated"].get<bool>();
    } catch (const std::exception&) {
    }
  }
  ASSERT_TRUE(calibrated) << st.dump() << slurp_file((dir / "mocapd.log.err").string());
  for (const auto& s : st["sensors"]) {
    EXPECT_TRUE(s["calibrated"].get<bool>()) << s.dump();
    // Each sensor's mounting and heading alignment: where it came from and how sure.
    EXPECT_NE(s["mounting"]["source"].get<std::string>(), "none") << s.dump();
    EXPECT_LT(s["mounting"]["sigma_deg"].get<double>(), 90) << s.dump();
    EXPECT_TRUE(s["alignment_heading"].contains("rejected_turns")) << s.dump();
    EXPECT_TRUE(s["alignment_heading"].contains("corrected_turns")) << s.dump();
    EXPECT_TRUE(s["alignment_heading"]["lost"].is_boolean()) << s.dump();  // a dropout's
    EXPECT_TRUE(s["alignment_heading"]["lost_count"].is_number()) << s.dump();
  }
  // A mounting calibration is taken and says what to do.
  {
    std::string reply;
    ASSERT_EQ(run({kBin + "mocapctl", "--socket", sock, "calibrate", "mounting"}, &reply), 0)
        << reply;
    EXPECT_NE(reply.find("bend the knees"), std::string::npos) << reply;
  }
  // The status tells how the calibration went and how far the performer stood from the pose.
  EXPECT_EQ(st["calibration"]["message"].get<std::string>().rfind("calibrated in npose", 0), 0u)
      << st.dump();
  std::string table;
  ASSERT_EQ(run({kBin + "mocapctl", "--socket", sock, "status"}, &table), 0);
  EXPECT_NE(table.find("calibration: calibrated in npose"), std::string::npos) << table;
  EXPECT_NE(table.find("furthest from the npose"), std::string::npos) << table;

  auto lines = read_json_lines(port, 60);
  ASSERT_EQ(lines.size(), 60u);
  for (const auto& l : lines) {
    std::map<std::string, nlohmann::json> seg;
    for (const auto& s : l["segments"])
      seg[s["name"].get<std::string>()] = s;
    const auto z = [&](const char* n) { return seg.at(n)["p"][2].get<double>(); };
    EXPECT_GT(z("head") - z("pelvis"), 0.35) << l.dump();
    for (const char* foot : {"foot_l", "foot_r"}) {
      // Near the floor: the performer may already be walking (a loaded machine reads these
      // lines later), and a swing foot rises up to about 0.3 m.
      EXPECT_LT(z(foot) - z("pelvis"), -0.5) << l.dump();
      EXPECT_LT(z(foot), 0.4) << l.dump();
      EXPECT_GT(z(foot), -0.1) << l.dump();
    }
    // Pelvis up axis (third column of its rotation) within 30 degrees of earth up.
    const auto& q = seg.at("pelvis")["q"];
    const double w = q[0], x = q[1], y = q[2], zq = q[3];
    const double up_z = 1 - 2 * (x * x + y * y);
    EXPECT_GT(up_z, std::cos(30 * 3.14159265 / 180)) << q.dump() << " w=" << w << zq;
  }
  kill(d, SIGTERM);
  EXPECT_EQ(wait_exit(d), 0) << slurp_file((dir / "mocapd.log.err").string());
  guard.pid = -1;
  fs::remove_all(dir);
}

// Any BVH file as the demo's motion: `mocap perform` writes a 1.60 m performer's walk as BVH,
// `mocapd --demo` plays it through the calibration procedure and the simulated devices, and the
// streamed avatar has the file's bones (shank length), not the default 1.75 m body's.
TEST(Mocapd, DemoPlaysABvhFileWithItsBones) {
  const fs::path dir = fs::temp_directory_path() / ("mocap-e2e-bvh-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string bvh = (dir / "walk160.bvh").string();
  std::string out;
  ASSERT_EQ(
      run({kBin + "mocap", "perform", "--motion", "walk", "--body-height", "1.60", "--bvh", bvh},
          &out),
      0)
      << out;
  const std::string sock = (dir / "ctl.sock").string();
  const uint16_t port = free_port();
  const pid_t d =
      spawn({kBin + "mocapd", "--demo", "--set", "demo.motion=calibrate+" + bvh, "--set",
             "daemon.control_socket=" + sock, "--set", "outputs.json.port=" + std::to_string(port),
             "--set", "outputs.posture.shm_name=/mocap-e2e-bvh-" + std::to_string(getpid()),
             "--log-level", "info"},
            (dir / "mocapd.log").string());
  bool calibrated = false;
  for (int i = 0; i < 150 && !calibrated; ++i) {
    std::this_thread::sleep_for(100ms);
    if (run({kBin + "mocapctl", "--socket", sock, "status", "--json"}, &out) != 0) continue;
    try {
      calibrated = nlohmann::json::parse(out)["calibrated"].get<bool>();
    } catch (const std::exception&) {
    }
  }
  ASSERT_TRUE(calibrated) << out << slurp_file((dir / "mocapd.log.err").string());
  const double shank_160_m = mocap::body_dimensions_from_height(1.60)
                                 .joint_offset_m[mocap::index(mocap::Segment::foot_l)]
                                 .norm();
  const double shank_175_m = mocap::body_dimensions_from_height(1.75)
                                 .joint_offset_m[mocap::index(mocap::Segment::foot_l)]
                                 .norm();
  ASSERT_GT(shank_175_m - shank_160_m, 0.03);
  const auto lines = read_json_lines(port, 30);
  ASSERT_EQ(lines.size(), 30u);
  for (const auto& l : lines) {
    std::map<std::string, nlohmann::json> seg;
    for (const auto& s : l["segments"])
      seg[s["name"].get<std::string>()] = s;
    const auto& a = seg.at("shank_l")["p"];
    const auto& b = seg.at("foot_l")["p"];
    const double shank_m =
        std::hypot(a[0].get<double>() - b[0].get<double>(), a[1].get<double>() - b[1].get<double>(),
                   a[2].get<double>() - b[2].get<double>());
    EXPECT_NEAR(shank_m, shank_160_m, 1e-3) << l.dump();
  }
  kill(d, SIGTERM);
  EXPECT_EQ(wait_exit(d), 0) << slurp_file((dir / "mocapd.log.err").string());
  fs::remove_all(dir);
}

// VRChat OSC trackers from the real daemon to liblo's oscdump: once the demo has calibrated
// itself, every slot and the head arrive as three floats, at heights a walking performer's
// hip, feet and head have; the sink scales positions by outputs.vrchat.height_m (1.925 m over
// the 1.75 m body: 1.1, as it logs).
TEST(Mocapd, DemoSendsVrchatTrackersThatOscdumpReceives) {
  if (::access("/usr/bin/oscdump", X_OK) != 0) GTEST_SKIP() << "oscdump (liblo-tools) missing";
  const fs::path dir = fs::temp_directory_path() / ("mocap-e2e-vrc-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string sock = (dir / "ctl.sock").string();
  const std::string osc_port = std::to_string(free_port());
  const pid_t dump = spawn({"/usr/bin/oscdump", "-L", osc_port}, (dir / "osc.txt").string());
  const pid_t d =
      spawn({kBin + "mocapd", "--demo", "--set", "daemon.control_socket=" + sock, "--set",
             "outputs.json.port=" + std::to_string(free_port()), "--set",
             "outputs.posture.shm_name=/mocap-e2e-vrc-" + std::to_string(getpid()), "--set",
             "outputs.vrchat.enabled=true", "--set", "outputs.vrchat.port=" + osc_port, "--set",
             "outputs.vrchat.height_m=1.925", "--log-level", "info"},
            (dir / "mocapd.log").string());
  bool calibrated = false;
  std::string out;
  for (int i = 0; i < 250 && !calibrated; ++i) {
    std::this_thread::sleep_for(100ms);
    if (run({kBin + "mocapctl", "--socket", sock, "status", "--json"}, &out) != 0) continue;
    try {
      calibrated = nlohmann::json::parse(out)["calibrated"].get<bool>();
    } catch (const std::exception&) {
    }
  }
  const std::size_t calibrated_at = slurp_file((dir / "osc.txt").string()).size();
  if (calibrated) std::this_thread::sleep_for(1000ms);
  kill(d, SIGTERM);
  EXPECT_EQ(wait_exit(d), 0) << slurp_file((dir / "mocapd.log.err").string());
  kill(dump, SIGTERM);
  wait_exit(dump);
  ASSERT_TRUE(calibrated) << out << slurp_file((dir / "mocapd.log.err").string());

  // Lines "<timetag> <address> fff x y z" after the calibration.
  std::istringstream in(slurp_file((dir / "osc.txt").string()).substr(calibrated_at));
  std::string line;
  std::getline(in, line);  // possibly cut at calibrated_at
  std::map<std::string, int> count;
  std::map<std::string, std::array<double, 3>> last;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string tt, address, types;
    std::array<double, 3> v{};
    ls >> tt >> address >> types >> v[0] >> v[1] >> v[2];
    if (ls.fail()) continue;  // a line cut by SIGTERM
    EXPECT_EQ(address.rfind("/tracking/trackers/", 0), 0u) << line;
    EXPECT_EQ(types, "fff") << line;
    ++count[address];
    last[address] = v;
  }
  const std::vector<std::string> slots = {"1", "2", "3", "4", "5", "6", "7", "8", "head"};
  for (const auto& s : slots)
    for (const char* kind : {"/position", "/rotation"}) {
      const std::string a = "/tracking/trackers/" + s + kind;
      EXPECT_GE(count[a], 5) << a;  // up to 100 Hz for a second (fewer on a loaded machine)
    }
  // The sink scales positions by 1.925 / 1.75; Unity y is up: the hip (slot 1), the feet (3,
  // 4) near the floor and the head at a walking performer's heights (0.93 m and 1.54 m standing
  // at 1.75 m, times 1.1).
  EXPECT_NE(slurp_file((dir / "mocapd.log.err").string()).find("position scale 1.100"),
            std::string::npos)
      << slurp_file((dir / "mocapd.log.err").string());
  const double hip = last["/tracking/trackers/1/position"][1],
               foot_l = last["/tracking/trackers/3/position"][1],
               foot_r = last["/tracking/trackers/4/position"][1],
               head = last["/tracking/trackers/head/position"][1];
  const std::string heights = "hip " + std::to_string(hip) + " feet " + std::to_string(foot_l) +
                              " " + std::to_string(foot_r) + " head " + std::to_string(head);
  EXPECT_GT(hip, 0.75) << heights;
  EXPECT_LT(hip, 1.15) << heights;
  EXPECT_LT(foot_l, 0.25) << heights;
  EXPECT_LT(foot_r, 0.25) << heights;
  EXPECT_GT(head, 1.35) << heights;
  EXPECT_LT(head, 1.85) << heights;
  fs::remove_all(dir);
}

namespace {

// The path an outside evaluator takes: a performance of a real CMU clip written as sample and
// truth CSVs, replayed through the tracker with a calibration at a moment of the file (9D and
// 6D: never refused), scored with the dataset README's metric by `mocap score`.
TEST(Score, ReplayOfARealClipIsScoredAgainstItsTruth) {
  const fs::path dir = fs::temp_directory_path() / ("mocap-score-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string samples = (dir / "s.csv").string(), truth = (dir / "t.csv").string();
  const std::string clip = std::string(MOCAP_SHARED_DIR) + "/datasets/cmu/02_01.bvh";
  ASSERT_EQ(run({kBin + "mocap", "perform", "--motion", "calibrate+" + clip, "--samples", samples,
                 "--truth", truth}),
            0);
  for (const char* use_mag : {"true", "false"}) {
    const std::string poses = (dir / (std::string("p_") + use_mag + ".csv")).string();
    std::string out;
    ASSERT_EQ(run({kBin + "mocap", "replay", samples, "--calibrate", "npose@1.5", "--set",
                   std::string("filter.use_mag=") + use_mag, "--csv", poses, "--quiet"},
                  &out),
              0)
        << out;
    EXPECT_NE(out.find("calibrated in npose"), std::string::npos) << out;
    // The clip starts after the 3 s stand and 4.2 s of calibration moves.
    ASSERT_EQ(run({kBin + "mocap", "score", poses, truth, "--from", "7.2"}, &out), 0) << out;
    const auto j = nlohmann::json::parse(out);
    EXPECT_GT(j["frames"].get<int>(), 200) << out;
    // Measured 1.24 (9D) and 3.26 deg (6D; docs/accuracy.md): regression guards.
    EXPECT_LT(j["mean_segment_error_deg"].get<double>(), std::string(use_mag) == "true" ? 2.0 : 5.0)
        << out;
  }
  std::string out;
  EXPECT_EQ(run({kBin + "mocap", "score", samples, truth}, &out), 1);  // not a pose file
  const std::string err = slurp_file(fs::temp_directory_path() /
                                     ("mocap-e2e-out-" + std::to_string(getpid()) + ".err"));
  EXPECT_NE(err.find("not a unit quaternion"), std::string::npos) << err;
  fs::remove_all(dir);
}

}  // namespace

namespace {

// `mocapd --replay SESSION --set K=V` without --config changes the recorded configuration (it
// was silently ignored): the recorded session had no JSON stream; it comes on the port given.
TEST(Mocapd, ReplaySetWithoutConfigChangesTheRecordedConfiguration) {
  const std::string session = std::string(MOCAP_SOURCE_DIR) + "/tests/data/demo_direct_50hz.mcap";
  const uint16_t port = free_port();
  const pid_t d =
      spawn({kBin + "mocapd", "--replay", session, "--speed", "1", "--set",
             "outputs.json.enabled=true", "--set", "outputs.json.port=" + std::to_string(port),
             "--set", "outputs.posture.shm_name=/mocap-e2e-replay-" + std::to_string(getpid())},
            (fs::temp_directory_path() / ("mocap-e2e-replay-" + std::to_string(getpid()) + ".log"))
                .string());
  std::vector<nlohmann::json> lines;
  for (int i = 0; i < 50 && lines.empty(); ++i) {  // until the daemon listens
    std::this_thread::sleep_for(100ms);
    lines = read_json_lines(port, 5);
  }
  EXPECT_EQ(lines.size(), 5u);
  // A replay gives the recorded wall clock back: the session's realtime - monotonic offset.
  {
    mocap::SessionReader r;
    std::string err;
    ASSERT_TRUE(r.open(session, &err)) << err;
    const int64_t recorded = r.header().t_start_unix_ns - r.header().t_start_host_ns;
    for (const auto& l : lines)
      EXPECT_EQ(l["t_unix_ns"].get<int64_t>() - l["t_ns"].get<int64_t>(), recorded) << l["frame"];
  }
  kill(d, SIGTERM);
  EXPECT_GE(wait_exit(d), 0);
}

}  // namespace
