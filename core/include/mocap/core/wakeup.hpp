// Wakes a sleeping consumer thread (the pipeline) when a producer has pushed data. Backed by an
// eventfd, so it can also be waited on together with sockets in poll().
#pragma once

#include <cstdint>

namespace mocap {

class Wakeup {
 public:
  Wakeup();
  ~Wakeup();
  Wakeup(const Wakeup&) = delete;
  Wakeup& operator=(const Wakeup&) = delete;

  /// Any thread: make the next (or current) wait() return. Async-signal-safe.
  void notify() noexcept;
  /// Consumer: block until notified or timeout_ms passes (-1 = forever). Returns true if
  /// notified. Clears the pending notifications.
  bool wait(int timeout_ms) noexcept;
  /// The file descriptor, readable while a notification is pending.
  int fd() const { return fd_; }

 private:
  int fd_ = -1;
};

}  // namespace mocap
