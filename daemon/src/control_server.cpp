// The control socket's server thread and client call: AF_UNIX stream socket, mode 0600, one
// bounded request line per connection; connections served independently (non-blocking, one
// poll loop, per-connection buffers and deadlines) so a silent client delays nobody.
#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "mocap/core/time.hpp"
#include "mocap/core/unix_line_client.hpp"
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
  for (auto& c : conns_)
    ::close(c.fd);
  conns_.clear();
  if (reserve_fd_ >= 0) ::close(reserve_fd_);
  ::close(listen_fd_);
  ::unlink(path_.c_str());
}

namespace {
constexpr int64_t kRequestTimeoutNs = 2'000'000'000;
constexpr int64_t kAcceptPauseNs = 100'000'000;
}  // namespace

void ControlServer::run() {
  reserve_fd_ = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  std::vector<pollfd> fds;
  fds.reserve(kMaxControlConnections + 2);
  int64_t last_exhausted_log = 0;
  while (!stopping_) {
    int64_t now = monotonic_ns();
    const bool accepting = now >= accept_paused_until_;
    fds.clear();
    fds.push_back({stop_.fd(), POLLIN, 0});
    fds.push_back({accepting ? listen_fd_ : -1, POLLIN, 0});
    int64_t wake = now + 1'000'000'000;
    if (!accepting) wake = std::min(wake, accept_paused_until_);
    for (const auto& c : conns_) {
      fds.push_back({c.fd, static_cast<short>(c.replying ? POLLOUT : POLLIN), 0});
      wake = std::min(wake, c.deadline_ns);
    }
    const int timeout_ms =
        static_cast<int>(std::max<int64_t>(0, (wake - now + 999'999) / 1'000'000));
    const int n = ::poll(fds.data(), fds.size(), timeout_ms);
    if (n < 0 && errno != EINTR) {
      log_.error("control poll: %s", std::strerror(errno));
      return;
    }
    if (stopping_) break;
    now = monotonic_ns();
    // Connections first, backwards: closing swaps the last one into the freed place.
    for (std::size_t i = conns_.size(); i > 0; --i) {
      Conn& c = conns_[i - 1];
      const short re = n > 0 ? fds[i + 1].revents : 0;
      bool keep = true;
      if (re) {
        if (c.replying)
          keep = (re & (POLLERR | POLLHUP | POLLNVAL)) ? false : send_reply(c);
        else
          keep = on_input(c, re);
      }
      if (keep && now >= c.deadline_ns) {
        if (!c.replying) {
          answer(c, false, false);  // "incomplete request", best effort
          send_reply(c);
        }
        keep = false;
      }
      if (!keep) close_conn(i - 1);
    }
    if (accepting && n > 0 && (fds[1].revents & POLLIN)) accept_connections(now);
    if (accept_paused_until_ > now && now - last_exhausted_log > 10'000'000'000) {
      last_exhausted_log = now;
      log_.warn("control socket: out of file descriptors; accepting paused briefly");
    }
  }
}

void ControlServer::accept_connections(int64_t now) {
  for (int k = 0; k < 16; ++k) {
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC | SOCK_NONBLOCK);
    if (fd < 0) {
      if (errno == EMFILE || errno == ENFILE) {
        if (reserve_fd_ >= 0) {  // give up the reserve: the next accept takes its place
          ::close(reserve_fd_);
          reserve_fd_ = -1;
          continue;
        }
        accept_paused_until_ = now + kAcceptPauseNs;  // never a busy loop on a full table
      } else if (errno == ECONNABORTED || errno == EINTR) {
        continue;
      }
      return;
    }
    if (conns_.size() >= kMaxControlConnections) {
      // Full: the oldest connection still waiting for its request makes room.
      std::size_t oldest = conns_.size();
      for (std::size_t i = 0; i < conns_.size(); ++i)
        if (!conns_[i].replying &&
            (oldest == conns_.size() || conns_[i].accepted_ns < conns_[oldest].accepted_ns))
          oldest = i;
      if (oldest == conns_.size()) {
        ::close(fd);
        continue;
      }
      close_conn(oldest);
    }
    Conn c;
    c.fd = fd;
    c.accepted_ns = now;
    c.deadline_ns = now + kRequestTimeoutNs;
    conns_.push_back(std::move(c));
  }
}

bool ControlServer::on_input(Conn& c, short revents) {
  char chunk[512];
  bool eof = false;
  for (;;) {
    const ssize_t n = ::recv(c.fd, chunk, sizeof chunk, 0);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) break;
    if (n <= 0) {
      eof = true;
      break;
    }
    for (ssize_t i = 0; i < n; ++i) {
      if (chunk[i] == '\n') {
        answer(c, true, false);
        return c.replying ? send_reply(c) : false;
      }
      c.in.push_back(chunk[i]);
    }
    if (c.in.size() > kMaxControlRequest) {
      answer(c, false, true);
      return send_reply(c);
    }
  }
  if (eof || (revents & (POLLERR | POLLHUP | POLLNVAL))) {
    if (revents & (POLLERR | POLLNVAL)) return false;
    // EOF ends the request too (a client that shut down its sending side and waits); answer()
    // drops it if the client has hung up entirely.
    if (!c.in.empty()) {
      answer(c, true, false);
      return c.replying && send_reply(c);
    }
    if (revents & POLLHUP) return false;
    answer(c, false, false);
    return send_reply(c);
  }
  return true;
}

void ControlServer::answer(Conn& c, bool complete, bool too_long) {
  std::string reply;
  std::string error;
  if (too_long) {
    reply = control_error_reply("request too long (max " + std::to_string(kMaxControlRequest) +
                                " bytes)");
  } else if (!complete) {
    reply = control_error_reply("incomplete request (expected one line ending in newline)");
  } else if (auto req = parse_control_request(c.in, error)) {
    // A client that hung up (timed out and closed) does not get its command run later.
    pollfd p{c.fd, POLLOUT, 0};
    if (::poll(&p, 1, 0) > 0 && (p.revents & (POLLHUP | POLLERR))) {
      ++abandoned_;
      log_.warn("control request '%.64s' dropped: the client hung up before it ran", c.in.c_str());
      c.replying = false;
      return;
    }
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
  c.out = reply + "\n";
  c.out_pos = 0;
  c.replying = true;
  c.deadline_ns = monotonic_ns() + kRequestTimeoutNs;
}

bool ControlServer::send_reply(Conn& c) {
  while (c.out_pos < c.out.size()) {
    const ssize_t n = ::send(c.fd, c.out.data() + c.out_pos, c.out.size() - c.out_pos,
                             MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) return true;
    if (n <= 0) return false;
    c.out_pos += static_cast<std::size_t>(n);
  }
  return false;  // all sent: close
}

void ControlServer::close_conn(std::size_t i) {
  ::close(conns_[i].fd);
  if (i + 1 != conns_.size()) conns_[i] = std::move(conns_.back());
  conns_.pop_back();
  if (reserve_fd_ < 0) reserve_fd_ = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
}

std::string control_call(const std::string& path, std::string_view request_line, int timeout_ms) {
  return unix_line_call(path, request_line, timeout_ms, "mocapd");
}

}  // namespace mocap::daemon
