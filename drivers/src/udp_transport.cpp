// UDP input for wireless sensors: a socket bound to a configurable address; each read returns
// one datagram.
#include <netdb.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "fd_wait.hpp"
#include "mocap/drivers/transport.hpp"
#include "udp_socket.hpp"

namespace mocap {
namespace {

class UdpTransport final : public ByteTransport {
 public:
  UdpTransport(int fd, std::string name) : fd_(fd), name_(std::move(name)) {}
  ~UdpTransport() override { ::close(fd_); }
  ReadResult read(std::span<uint8_t> buf, int timeout_ms, int wake_fd) override {
    ReadResult r = wait_fd(fd_, wake_fd, timeout_ms);
    if (r.kind != ReadResult::kData) return r;
    const ssize_t n = ::recv(fd_, buf.data(), buf.size(), MSG_DONTWAIT);
    if (n < 0) {
      r.kind = ReadResult::kTimeout;
      return r;
    }
    r.n = static_cast<std::size_t>(n);
    return r;
  }
  bool write(std::span<const uint8_t>, std::string& err) override {
    err = name_ + ": UDP input is receive-only";
    return false;
  }
  bool record_framed() const override { return true; }
  std::string describe() const override { return "udp " + name_; }

 private:
  int fd_;
  std::string name_;
};

}  // namespace

bool split_host_port(const std::string& hp, std::string& host, std::string& port,
                     std::string& err) {
  const auto c = hp.rfind(':');
  if (c == std::string::npos || c + 1 == hp.size()) {
    err = "\"" + hp + "\": expected HOST:PORT, e.g. 0.0.0.0:9000";
    return false;
  }
  host = hp.substr(0, c);
  port = hp.substr(c + 1);
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']')
    host = host.substr(1, host.size() - 2);
  return true;
}

int bind_udp(const std::string& host_port, bool ipv4_only, bool broadcast, std::string& err) {
  std::string host, port;
  if (!split_host_port(host_port, host, port, err)) return -1;
  addrinfo hints{};
  hints.ai_family = ipv4_only ? AF_INET : AF_UNSPEC;
  hints.ai_socktype = SOCK_DGRAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* res = nullptr;
  const int rc = getaddrinfo(host.empty() ? nullptr : host.c_str(), port.c_str(), &hints, &res);
  if (rc != 0) {
    err = "udp " + host_port + ": " + gai_strerror(rc);
    return -1;
  }
  const int fd = ::socket(res->ai_family, res->ai_socktype | SOCK_CLOEXEC, 0);
  const int one = 1;
  if (fd >= 0 && broadcast) ::setsockopt(fd, SOL_SOCKET, SO_BROADCAST, &one, sizeof one);
  if (fd < 0 || ::bind(fd, res->ai_addr, res->ai_addrlen) != 0) {
    err = "udp " + host_port + ": cannot bind: " + std::strerror(errno);
    if (fd >= 0) ::close(fd);
    freeaddrinfo(res);
    return -1;
  }
  freeaddrinfo(res);
  return fd;
}

std::unique_ptr<ByteTransport> open_udp(const std::string& host_port, std::string& err) {
  const int fd = bind_udp(host_port, /*ipv4_only=*/false, /*broadcast=*/false, err);
  if (fd < 0) return nullptr;
  return std::make_unique<UdpTransport>(fd, host_port);
}

}  // namespace mocap
