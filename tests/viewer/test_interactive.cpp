// The interactive window driven like a user does, through the X server's input (xdotool, XTEST):
// a keypress N, T or H reaches the daemon's real control server as the matching request, the
// window asks a live daemon for its status once a second (the HUD's calibration prompt), and
// Q closes the window with exit status 0. Label gl: runs under Xvfb.
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "mocap/daemon/control.hpp"
#include "mocap/outputs/posture_shm.hpp"

extern char** environ;

namespace mocap {
namespace {

using namespace std::chrono_literals;

std::string run_out(const std::string& cmd) {
  std::string out;
  if (FILE* p = popen(cmd.c_str(), "r")) {
    char buf[256];
    while (std::fgets(buf, sizeof buf, p))
      out += buf;
    pclose(p);
  }
  while (!out.empty() && (out.back() == '\n' || out.back() == ' '))
    out.pop_back();
  return out;
}

/// Waits until pred() holds, up to timeout; returns whether it did.
template <typename Pred>
bool wait_for(Pred pred, std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < end) {
    if (pred()) return true;
    std::this_thread::sleep_for(20ms);
  }
  return pred();
}

TEST(InteractiveViewer, KeysReachTheDaemonAndQQuits) {
  if (!std::getenv("DISPLAY")) GTEST_SKIP() << "needs a display: run under xvfb-run";
  if (std::system("command -v xdotool > /dev/null") != 0)
    GTEST_SKIP() << "xdotool not installed (scripts/install-deps.sh --test installs it)";
  const std::string tag = std::to_string(getpid());
  const std::string sock = "/tmp/mocap-viewer-keys-" + tag + ".sock";
  std::mutex mu;
  std::vector<daemon::ControlRequest> seen;
  std::atomic<int> status_requests{0};
  LogSink sink;
  daemon::ControlServer server(
      sock,
      [&](const daemon::ControlRequest& r) {
        if (r.command == daemon::ControlCommand::status) {
          ++status_requests;
          return std::string(R"({"ok":true,"calibrated":false,"calibration":{"message":""}})");
        }
        std::lock_guard lock(mu);
        seen.push_back(r);
        return std::string(R"({"ok":true,"message":"ok"})");
      },
      Logger(sink, "test", LogLevel::warn));
  // A live source: the shared posture, as a daemon writes it.
  outputs::PostureWriter posture("/mocap-viewer-keys-" + tag);
  PoseFrame f;
  reset_pose(f);
  for (auto& p : f.p_earth_segment_m)
    p = {0, 0, 1};
  posture.publish(f);

  // Under ASan the GL driver (dlclosed at exit) reports small leaks: not the viewer's
  // (docs/viewer.md); ASan reads this at start-up, so only the children see it.
  const char* asan = std::getenv("ASAN_OPTIONS");
  setenv("ASAN_OPTIONS", (std::string(asan ? asan : "") + ":detect_leaks=0").c_str(), 1);
  const std::string exe = MOCAP_VIEWER_EXE;
  std::vector<std::string> args = {exe,  "--shm",  posture.name(), "--socket",
                                   sock, "--size", "640x360",      "--no-vsync"};
  std::vector<char*> argv;
  for (auto& a : args)
    argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = -1;
  ASSERT_EQ(posix_spawn(&pid, exe.c_str(), nullptr, nullptr, argv.data(), environ), 0);

  // The window, by its title; focus it so XTEST key events go to it.
  std::string window;
  ASSERT_TRUE(wait_for(
      [&] {
        window = run_out("xdotool search --name '^mocap-viewer$' 2>/dev/null | head -1");
        return !window.empty();
      },
      15s))
      << "no viewer window";
  std::system(("xdotool windowfocus --sync " + window + " 2>/dev/null").c_str());
  std::this_thread::sleep_for(300ms);
  const auto requests = [&] {
    std::lock_guard lock(mu);
    return seen;
  };
  for (const char* key : {"n", "t", "h"}) {
    const size_t before = requests().size();
    ASSERT_EQ(std::system(("xdotool key " + std::string(key)).c_str()), 0);
    EXPECT_TRUE(wait_for([&] { return requests().size() > before; }, 5s)) << "key " << key;
  }
  const auto got = requests();
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0].command, daemon::ControlCommand::calibrate);
  EXPECT_EQ(got[0].argument, "npose");
  EXPECT_EQ(got[1].command, daemon::ControlCommand::calibrate);
  EXPECT_EQ(got[1].argument, "tpose");
  EXPECT_EQ(got[2].command, daemon::ControlCommand::reset_heading);
  // The HUD's status polling (once a second, live source).
  EXPECT_TRUE(wait_for([&] { return status_requests.load() >= 2; }, 5s)) << status_requests.load();

  ASSERT_EQ(std::system("xdotool key q"), 0);
  int st = 0;
  const bool exited = wait_for([&] { return waitpid(pid, &st, WNOHANG) == pid; }, 10s);
  if (!exited) {
    kill(pid, SIGKILL);
    waitpid(pid, nullptr, 0);
  }
  ASSERT_TRUE(exited) << "Q did not close the viewer";
  EXPECT_TRUE(WIFEXITED(st) && WEXITSTATUS(st) == 0) << st;
}

}  // namespace
}  // namespace mocap
