// Streams people can use and keep private (issue 21 item 5, issue 20 "JSON stream"), against
// the real mocapd: the example Python client (examples/joint_angles.py, run by the real python3)
// prints joint angles with frame counters and UTC wall-clock times over TCP; the private stream
// on a Unix socket is mode 0600, serves the same client, and refuses another user.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "harness.hpp"

using namespace mocap;
using namespace mocap::reliability;
using namespace std::chrono_literals;

namespace {

/// Runs examples/joint_angles.py ADDRESS FRAMES with python3; its exit code and stdout+stderr.
int run_example(const std::string& address, int frames, std::string& out) {
  const std::string cmd = "timeout 30 python3 '" + std::string(MOCAP_SOURCE_DIR) +
                          "/examples/joint_angles.py' '" + address + "' " + std::to_string(frames) +
                          " 2>&1";
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return -1;
  char buf[4096];
  out.clear();
  while (size_t n = std::fread(buf, 1, sizeof buf, p))
    out.append(buf, n);
  const int st = ::pclose(p);
  return WIFEXITED(st) ? WEXITSTATUS(st) : 128;
}

int64_t now_unix_ns() {
  timespec ts{};
  ::clock_gettime(CLOCK_REALTIME, &ts);
  return ts.tv_sec * 1'000'000'000ll + ts.tv_nsec;
}

/// Checks the example's output: `frames` lines, increasing frame counters, a UTC time within
/// the last `max_age_s`, and all 15 joints with an angle in [0, 180] degrees.
void check_example_output(const std::string& out, int frames, int64_t started_unix_ns) {
  static const char* kJoints[] = {"torso",   "neck",        "head",      "upper_arm_l", "forearm_l",
                                  "hand_l",  "upper_arm_r", "forearm_r", "hand_r",      "thigh_l",
                                  "shank_l", "foot_l",      "thigh_r",   "shank_r",     "foot_r"};
  const std::regex head(
      R"(^frame (\d+) (\d{4})-(\d\d)-(\d\d)T(\d\d):(\d\d):(\d\d)\.(\d{6})\+00:00 )");
  std::istringstream in(out);
  std::string line;
  int n = 0;
  long long last_frame = -1;
  while (std::getline(in, line)) {
    ++n;
    std::smatch m;
    ASSERT_TRUE(std::regex_search(line, m, head)) << line;
    const long long frame = std::stoll(m[1]);
    EXPECT_GT(frame, last_frame) << line;
    last_frame = frame;
    std::tm tm{};
    tm.tm_year = std::stoi(m[2]) - 1900;
    tm.tm_mon = std::stoi(m[3]) - 1;
    tm.tm_mday = std::stoi(m[4]);
    tm.tm_hour = std::stoi(m[5]);
    tm.tm_min = std::stoi(m[6]);
    tm.tm_sec = std::stoi(m[7]);
    const int64_t t = static_cast<int64_t>(::timegm(&tm)) * 1'000'000'000ll +
                      std::stoll(m[8]) * 1000;  // the pose's UTC time, as printed
    EXPECT_GT(t, started_unix_ns - 60'000'000'000ll) << line;
    EXPECT_LE(t, now_unix_ns()) << line;
    for (const char* j : kJoints) {
      const std::regex angle(std::string(" ") + j + R"(=(\d+\.\d)( |$))");
      std::smatch a;
      ASSERT_TRUE(std::regex_search(line, a, angle)) << j << " in: " << line;
      const double deg = std::stod(a[1]);
      EXPECT_GE(deg, 0.0);
      EXPECT_LE(deg, 180.0);
    }
  }
  EXPECT_EQ(n, frames) << out;
}

}  // namespace

TEST(Streams, TheExamplePythonClientPrintsJointAnglesFromTheRealDaemon) {
  TempDir dir;
  const int port = free_tcp_port();
  // The demo performer (15 simulated sensors through the real drivers) calibrates itself, then
  // bends knees and elbows: the angles printed must move.
  Daemon d(dir, "example", base_config(dir, port), {"--demo"});
  ASSERT_TRUE(d.wait_ready(15s)) << d.log_text();
  ASSERT_TRUE(wait_until([&] { return d.status().value("calibrated", false); }, 60s))
      << d.log_text();
  const int64_t started = now_unix_ns();
  std::string out;
  constexpr int kFrames = 360;  // 3 s at 120 Hz
  ASSERT_EQ(run_example("127.0.0.1:" + std::to_string(port), kFrames, out), 0) << out;
  check_example_output(out, kFrames, started);
  double max_deg = 0;
  const std::regex any_angle(R"(=(\d+\.\d))");
  for (auto it = std::sregex_iterator(out.begin(), out.end(), any_angle);
       it != std::sregex_iterator(); ++it)
    max_deg = std::max(max_deg, std::stod((*it)[1]));
  EXPECT_GT(max_deg, 10.0) << out.substr(0, 2000);
  std::printf(
      "[figures] examples/joint_angles.py over TCP: %d frames, largest joint angle %.1f "
      "deg; first line: %s\n",
      kFrames, max_deg, out.substr(0, out.find('\n')).c_str());
  EXPECT_EQ(d.quit(), 0) << d.log_text();
}

TEST(Streams, ThePrivateStreamOnAUnixSocketIsMode0600AndClosedToOtherUsers) {
  TempDir dir;
  ASSERT_EQ(::chmod(dir.path().c_str(), 0755), 0);  // the directory itself does not protect it
  TwoSensorRig rig(dir);
  const std::string path = dir.file("pose.sock");
  std::string config = base_config(dir, free_tcp_port()) + rig.sensors_toml();
  const std::string table = "[outputs.json]\n";
  config.insert(config.find(table) + table.size(), "unix_socket = \"" + path + "\"\n");
  Daemon d(dir, "private", config);
  ASSERT_TRUE(d.wait_ready(15s)) << d.log_text();
  ASSERT_TRUE(wait_until([&] { return both_streaming(d); }, 15s)) << d.log_text();

  struct stat sb {};
  ASSERT_EQ(::lstat(path.c_str(), &sb), 0) << d.log_text();
  EXPECT_TRUE(S_ISSOCK(sb.st_mode));
  EXPECT_EQ(sb.st_mode & 0777, 0600u);
  EXPECT_EQ(sb.st_uid, ::geteuid());

  // Another client process of the same user (python3 running the example) reads frames.
  const int64_t started = now_unix_ns();
  std::string out;
  ASSERT_EQ(run_example(path, 3, out), 0) << out;
  check_example_output(out, 3, started);

  if (::geteuid() == 0) {  // another user (nobody) is refused by the kernel
    EXPECT_EQ(connect_unix_as_nobody(path), 0)
        << "1 = another user connected, 2 = unexpected errno, 3 = not nobody, -1 = died";
  }
  EXPECT_EQ(d.quit(), 0) << d.log_text();
  EXPECT_NE(::lstat(path.c_str(), &sb), 0);  // removed on exit
}
