// Non-blocking TCP client for the pose JSON stream.
#include "mocap/viewer/net_source.hpp"

#include <fcntl.h>
#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "mocap/viewer/pose_json.hpp"

namespace mocap::viewer {

NetSource::NetSource(const std::string& host_port) {
  const auto colon = host_port.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == host_port.size())
    throw std::runtime_error("--connect '" + host_port + "': expected HOST:PORT");
  host_ = host_port.substr(0, colon);
  port_ = host_port.substr(colon + 1);
  if (host_.front() == '[' && host_.back() == ']') host_ = host_.substr(1, host_.size() - 2);
  char* end = nullptr;
  const long port = std::strtol(port_.c_str(), &end, 10);
  if (*end != '\0' || port < 1 || port > 65535)
    throw std::runtime_error("--connect '" + host_port + "': port must be 1..65535");
  buffer_.reserve(2 * kMaxPoseJsonLine);
}

NetSource::~NetSource() {
  if (fd_ >= 0) close(fd_);
}

void NetSource::disconnect(const std::string& why, double t_s) {
  if (fd_ >= 0) close(fd_);
  fd_ = -1;
  connected_ = false;
  buffer_.clear();
  error_ = why;
  next_try_s_ = t_s + 1.0;
}

bool NetSource::start_connect(double t_s) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* res = nullptr;
  if (const int rc = getaddrinfo(host_.c_str(), port_.c_str(), &hints, &res); rc != 0) {
    disconnect(std::string("cannot resolve ") + host_ + ": " + gai_strerror(rc), t_s);
    return false;
  }
  fd_ = socket(res->ai_family, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  const int rc = fd_ < 0 ? -1 : connect(fd_, res->ai_addr, res->ai_addrlen);
  const int err = errno;
  freeaddrinfo(res);
  if (fd_ < 0 || (rc != 0 && err != EINPROGRESS)) {
    disconnect(std::string("connect: ") + std::strerror(err), t_s);
    return false;
  }
  connected_ = rc == 0;
  connect_deadline_s_ = t_s + 3.0;
  return true;
}

bool NetSource::poll(double t_s, std::vector<PoseFrame>& frames) {
  if (fd_ < 0) {
    if (t_s < next_try_s_ || !start_connect(t_s)) return false;
  }
  if (!connected_) {
    pollfd p{fd_, POLLOUT, 0};
    if (::poll(&p, 1, 0) <= 0) {
      if (t_s > connect_deadline_s_) disconnect("connect: timed out", t_s);
      return false;
    }
    int err = 0;
    socklen_t len = sizeof err;
    getsockopt(fd_, SOL_SOCKET, SO_ERROR, &err, &len);
    if (err != 0) {
      disconnect(std::string("connect: ") + std::strerror(err), t_s);
      return false;
    }
    connected_ = true;
    error_.clear();
  }
  // Read what has arrived (bounded per poll so a fast stream cannot stall the render loop).
  char chunk[16384];
  for (int i = 0; i < 16; ++i) {
    const ssize_t n = recv(fd_, chunk, sizeof chunk, 0);
    if (n > 0) {
      buffer_.append(chunk, static_cast<size_t>(n));
      continue;
    }
    if (n == 0) {
      disconnect("connection closed by the daemon", t_s);
      return false;
    }
    if (errno == EINTR) continue;
    if (errno == EAGAIN || errno == EWOULDBLOCK) break;
    disconnect(std::string("recv: ") + std::strerror(errno), t_s);
    return false;
  }
  // Parse only the newest complete line; older ones are superseded anyway.
  const size_t last_nl = buffer_.rfind('\n');
  bool changed = false;
  if (last_nl != std::string::npos) {
    const size_t start = last_nl == 0 ? std::string::npos : buffer_.rfind('\n', last_nl - 1);
    const size_t from = start == std::string::npos ? 0 : start + 1;
    const std::string_view line(buffer_.data() + from, last_nl - from);
    PoseFrame f;
    std::string err;
    if (!paused_ && !line.empty()) {
      if (parse_pose_json(line, f, err)) {
        frames.resize(1);
        frames[0] = f;
        ++good_lines_;
        changed = true;
      } else {
        ++bad_lines_;
        error_ = "bad line skipped: " + err;
      }
    }
    buffer_.erase(0, last_nl + 1);
  } else if (buffer_.size() > kMaxPoseJsonLine) {
    ++bad_lines_;
    error_ = "line longer than 64 KiB skipped";
    buffer_.clear();  // resynchronise at the next newline
  }
  return changed;
}

std::string NetSource::status() const {
  std::string s = (connected_ ? "CONNECTED " : "CONNECTING TO ") + host_ + ":" + port_;
  if (!error_.empty()) s += " (" + error_ + ")";
  return s;
}

}  // namespace mocap::viewer
