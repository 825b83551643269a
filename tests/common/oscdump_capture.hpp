// liblo's oscdump as a real third-party OSC receiver for the VMC and VRChat sender tests: runs
// it on a UDP port, feeds it frames until its output shows up and a few more, and returns what
// it printed (one "<timetag> <address> <types> args..." line a message).
#pragma once

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

namespace mocap::test {

inline constexpr const char* kOscdumpPath = "/usr/bin/oscdump";

/// True if liblo-tools' oscdump is installed (the tests skip without it).
inline bool have_oscdump() {
  return ::access(kOscdumpPath, X_OK) == 0;
}

/// What oscdump printed, and how many frames had been sent when its first output arrived
/// (-1: it printed nothing, or could not be started).
struct OscdumpCapture {
  std::string text;
  int frames_before_first_output = -1;
};

/// Starts `oscdump -L port`, then calls publish(k) for k = 0, 1, ... (reading oscdump's output
/// 30 ms after each) until its output has appeared and `frames_after` more frames went out,
/// 10 s at most (oscdump gives no readiness signal); collects the rest and stops it.
inline OscdumpCapture capture_oscdump(uint16_t port, const std::function<void(int)>& publish,
                                      int frames_after = 4) {
  OscdumpCapture cap;
  int out[2];
  if (::pipe2(out, O_CLOEXEC) != 0) return cap;
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(out[0]);
    ::close(out[1]);
    return cap;
  }
  if (pid == 0) {
    ::dup2(out[1], 1);
    const std::string p = std::to_string(port);
    ::execl(kOscdumpPath, "oscdump", "-L", p.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ::close(out[1]);
  const auto read_some = [&](int timeout_ms) {
    pollfd pfd{out[0], POLLIN, 0};
    while (::poll(&pfd, 1, timeout_ms) > 0) {
      char buf[65536];
      const ssize_t n = ::read(out[0], buf, sizeof buf);
      if (n <= 0) break;
      cap.text.append(buf, static_cast<std::size_t>(n));
    }
  };
  int k = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (
      std::chrono::steady_clock::now() < deadline &&
      (cap.frames_before_first_output < 0 || k < cap.frames_before_first_output + frames_after)) {
    publish(k++);
    read_some(30);
    if (cap.frames_before_first_output < 0 && !cap.text.empty()) cap.frames_before_first_output = k;
  }
  read_some(300);
  ::kill(pid, SIGTERM);
  ::waitpid(pid, nullptr, 0);
  ::close(out[0]);
  return cap;
}

}  // namespace mocap::test
