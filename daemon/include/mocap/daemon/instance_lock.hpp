// One mocapd per runtime directory: an exclusive flock on <dir>/mocapd.pid (which holds the
// holder's pid), taken before any device, port or shared memory is touched. The kernel drops
// the lock when the holder exits or is killed, so a crash never leaves a stale lock.
#pragma once

#include <sys/types.h>
#include <string>

namespace mocap::daemon {

class InstanceLock {
 public:
  /// Takes the lock on dir/mocapd.pid. Throws std::runtime_error: "already running (pid N)"
  /// when another process holds it, or a message naming the file on other failures.
  explicit InstanceLock(const std::string& dir);
  ~InstanceLock();
  InstanceLock(const InstanceLock&) = delete;
  InstanceLock& operator=(const InstanceLock&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  int fd_ = -1;
};

}  // namespace mocap::daemon
