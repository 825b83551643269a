// Waiting on a transport's file descriptor together with the device's wake-up fd (internal).
#pragma once

#include <poll.h>

#include <cerrno>
#include <cstring>
#include <string>

#include "mocap/drivers/transport.hpp"

namespace mocap {

/// Blocks until fd is readable (kData, n = 0: the caller reads), hangs up (kVanished), wake_fd
/// fires (kWoken) or the timeout passes (kTimeout).
inline ReadResult wait_fd(int fd, int wake_fd, int timeout_ms) {
  pollfd p[2] = {{fd, POLLIN, 0}, {wake_fd, POLLIN, 0}};
  const int n = ::poll(p, wake_fd >= 0 ? 2 : 1, timeout_ms);
  ReadResult r;
  if (n < 0) {
    if (errno == EINTR) return r;
    r.kind = ReadResult::kVanished;
    r.reason = std::string("poll: ") + std::strerror(errno);
    return r;
  }
  if (n == 0) return r;
  if (wake_fd >= 0 && (p[1].revents & POLLIN)) {
    r.kind = ReadResult::kWoken;
    return r;
  }
  if (p[0].revents & POLLIN) {
    r.kind = ReadResult::kData;
    return r;
  }
  if (p[0].revents & (POLLHUP | POLLERR | POLLNVAL)) {
    r.kind = ReadResult::kVanished;
    r.reason = (p[0].revents & POLLHUP) ? "hang-up (device unplugged or closed)" : "device error";
  }
  return r;
}

}  // namespace mocap
