// InstanceLock (instance_lock.hpp).
#include "mocap/daemon/instance_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace mocap::daemon {

InstanceLock::InstanceLock(const std::string& dir) : path_(dir + "/mocapd.pid") {
  fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0600);
  if (fd_ < 0)
    throw std::runtime_error("cannot open the instance lock " + path_ + ": " +
                             std::strerror(errno));
  struct stat st {};
  if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode) || st.st_uid != ::geteuid()) {
    ::close(fd_);
    throw std::runtime_error("instance lock " + path_ + " is not a regular file of ours (refused)");
  }
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int e = errno;
    char buf[32] = {};
    const ssize_t n = ::pread(fd_, buf, sizeof buf - 1, 0);
    ::close(fd_);
    fd_ = -1;
    if (e == EWOULDBLOCK) {
      long pid = n > 0 ? std::strtol(buf, nullptr, 10) : 0;
      throw std::runtime_error("already running (pid " + std::to_string(pid) + "): " + path_ +
                               " is locked; this instance changed nothing");
    }
    throw std::runtime_error("cannot lock " + path_ + ": " + std::strerror(e));
  }
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::ftruncate(fd_, 0) != 0 ||
      ::pwrite(fd_, pid.data(), pid.size(), 0) != static_cast<ssize_t>(pid.size())) {
    // The lock holds without the pid written; only the message of a second instance suffers.
  }
}

InstanceLock::~InstanceLock() {
  if (fd_ >= 0) {
    // Empty the pid file rather than unlinking it: unlinking a locked file lets a newcomer
    // lock a new inode while we still hold the old one.
    if (::ftruncate(fd_, 0) != 0) {
    }
    ::close(fd_);
  }
}

}  // namespace mocap::daemon
