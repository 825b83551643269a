// A listening Unix stream socket at a test's own path (any old socket file there removed), for
// tests that play the daemon's side of the control socket.
#pragma once

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstring>
#include <string>

namespace mocap::test {

/// The listening fd (-1 with a test failure if it cannot be made).
inline int listen_unix(const std::string& path, int backlog = 4) {
  unlink(path.c_str());
  const int fd = socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::strncpy(addr.sun_path, path.c_str(), sizeof addr.sun_path - 1);
  EXPECT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0) << path;
  EXPECT_EQ(listen(fd, backlog), 0) << path;
  return fd;
}

}  // namespace mocap::test
