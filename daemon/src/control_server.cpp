// The control socket's server thread and client call: AF_UNIX stream socket, mode 0600, one
// bounded request line per connection, per-connection timeouts so a stuck client cannot block
// the daemon.
#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "mocap/core/time.hpp"
#include "mocap/daemon/control.hpp"

namespace mocap::daemon {

namespace {

sockaddr_un make_addr(const std::string& path) {
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  if (path.size() >= sizeof a.sun_path)
    throw std::runtime_error("control socket path too long: " + path);
  std::memcpy(a.sun_path, path.c_str(), path.size() + 1);
  return a;
}

/// Connects with a timeout; returns the fd or -1 (errno set).
int connect_unix(const std::string& path) {
  const sockaddr_un a = make_addr(path);
  int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return -1;
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    const int e = errno;
    ::close(fd);
    errno = e;
    return -1;
  }
  return fd;
}

bool write_all(int fd, std::string_view data) {
  while (!data.empty()) {
    const ssize_t n = ::send(fd, data.data(), data.size(), MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    data.remove_prefix(static_cast<size_t>(n));
  }
  return true;
}

}  // namespace

ControlServer::ControlServer(std::string path, Handler handler, Logger log)
    : path_(std::move(path)), handler_(std::move(handler)), log_(std::move(log)) {
  const sockaddr_un a = make_addr(path_);
  struct stat st {};
  if (::lstat(path_.c_str(), &st) == 0) {
    if (!S_ISSOCK(st.st_mode))
      throw std::runtime_error("control socket path exists and is not a socket: " + path_);
    if (int fd = connect_unix(path_); fd >= 0) {
      ::close(fd);
      throw std::runtime_error("another mocapd is already listening on " + path_);
    }
    ::unlink(path_.c_str());  // stale socket of a daemon that died
  }
  listen_fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (listen_fd_ < 0) throw std::runtime_error("socket(): " + std::string(std::strerror(errno)));
  const mode_t old = ::umask(0177);  // the socket file is created 0600
  const int rc = ::bind(listen_fd_, reinterpret_cast<const sockaddr*>(&a), sizeof a);
  const int bind_errno = errno;
  ::umask(old);
  if (rc != 0 || ::chmod(path_.c_str(), 0600) != 0 || ::listen(listen_fd_, 16) != 0) {
    const std::string why = std::strerror(rc != 0 ? bind_errno : errno);
    ::close(listen_fd_);
    throw std::runtime_error("cannot listen on control socket " + path_ + ": " + why);
  }
  thread_ = std::thread([this] { run(); });
}

ControlServer::~ControlServer() {
  stopping_ = true;
  stop_.notify();
  if (thread_.joinable()) thread_.join();
  ::close(listen_fd_);
  ::unlink(path_.c_str());
}

void ControlServer::run() {
  while (!stopping_) {
    pollfd fds[2] = {{listen_fd_, POLLIN, 0}, {stop_.fd(), POLLIN, 0}};
    const int n = ::poll(fds, 2, 1000);
    if (n < 0 && errno != EINTR) {
      log_.error("control poll: %s", std::strerror(errno));
      return;
    }
    if (stopping_) break;
    if (n <= 0 || !(fds[0].revents & POLLIN)) continue;
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
    if (fd < 0) continue;
    serve_one(fd);
    ::close(fd);
  }
}

void ControlServer::serve_one(int fd) {
  // Read one line (bounded) within 2 s; then reply and close.
  std::string buf;
  buf.reserve(256);
  const int64_t deadline = monotonic_ns() + s_to_ns(2.0);
  bool complete = false, too_long = false;
  char chunk[512];
  while (!complete && !too_long) {
    const int64_t left_ms = (deadline - monotonic_ns()) / 1000000;
    if (left_ms <= 0) break;
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(left_ms)) <= 0) break;
    const ssize_t n = ::recv(fd, chunk, sizeof chunk, 0);
    if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
    if (n <= 0) {
      complete = !buf.empty();  // EOF ends the request too
      break;
    }
    for (ssize_t i = 0; i < n && !complete; ++i) {
      if (chunk[i] == '\n')
        complete = true;
      else
        buf.push_back(chunk[i]);
    }
    if (buf.size() > kMaxControlRequest) too_long = true;
  }
  std::string reply;
  std::string error;
  if (too_long) {
    reply = control_error_reply("request too long (max " + std::to_string(kMaxControlRequest) +
                                " bytes)");
  } else if (!complete) {
    reply = control_error_reply("incomplete request (expected one line ending in newline)");
  } else if (auto req = parse_control_request(buf, error)) {
    try {
      reply = handler_(*req);
    } catch (const std::exception& e) {
      reply = control_error_reply(e.what());
    }
  } else {
    reply = control_error_reply(error);
  }
  if (reply.rfind("{\"ok\":false", 0) == 0)
    log_.warn("control request rejected: %s", reply.c_str());
  ++served_;
  // Best effort: the client may have gone away. Make the socket blocking with a send timeout.
  ::fcntl(fd, F_SETFL, 0);
  timeval tv{1, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
  write_all(fd, reply + "\n");
}

std::string control_call(const std::string& path, std::string_view request_line, int timeout_ms) {
  const int fd = connect_unix(path);
  if (fd < 0)
    throw std::runtime_error("cannot reach mocapd at " + path + ": " + std::strerror(errno) +
                             " (is it running?)");
  std::string line(request_line);
  if (line.empty() || line.back() != '\n') line += '\n';
  if (!write_all(fd, line)) {
    ::close(fd);
    throw std::runtime_error("cannot send to mocapd at " + path);
  }
  std::string reply;
  char buf[4096];
  const int64_t deadline = monotonic_ns() + static_cast<int64_t>(timeout_ms) * 1000000;
  for (;;) {
    const int64_t left_ms = (deadline - monotonic_ns()) / 1000000;
    pollfd p{fd, POLLIN, 0};
    if (left_ms <= 0 || ::poll(&p, 1, static_cast<int>(left_ms)) <= 0) {
      ::close(fd);
      throw std::runtime_error("mocapd did not answer within " + std::to_string(timeout_ms) +
                               " ms");
    }
    const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    reply.append(buf, static_cast<size_t>(n));
    if (reply.size() > (1u << 24)) break;
  }
  ::close(fd);
  while (!reply.empty() && (reply.back() == '\n' || reply.back() == '\r'))
    reply.pop_back();
  return reply;
}

}  // namespace mocap::daemon
