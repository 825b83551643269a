// UDP sender for simulated wireless sensors (see sim_encoder.hpp).
#include <netdb.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstring>
#include <stdexcept>

#include "mocap/devsim/sim_encoder.hpp"
#include "mocap/drivers/transport.hpp"

namespace mocap {

UdpSender::UdpSender(const std::string& host_port) {
  std::string host, port, err;
  if (!split_host_port(host_port, host, port, err)) throw std::runtime_error(err);
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* res = nullptr;
  const int rc = getaddrinfo(host.c_str(), port.c_str(), &hints, &res);
  if (rc != 0) throw std::runtime_error("udp " + host_port + ": " + gai_strerror(rc));
  fd_ = ::socket(res->ai_family, res->ai_socktype | SOCK_CLOEXEC, 0);
  const bool ok = fd_ >= 0 && ::connect(fd_, res->ai_addr, res->ai_addrlen) == 0;
  freeaddrinfo(res);
  if (!ok) throw std::runtime_error("udp " + host_port + ": " + std::strerror(errno));
}

UdpSender::~UdpSender() {
  if (fd_ >= 0) ::close(fd_);
}

bool UdpSender::send(std::span<const uint8_t> bytes) {
  return ::send(fd_, bytes.data(), bytes.size(), MSG_DONTWAIT) ==
         static_cast<ssize_t>(bytes.size());
}

}  // namespace mocap
