// OSC 1.0 message and bundle encoding into fixed buffers (big-endian numbers, padded strings).
#include "mocap/outputs/osc.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <bit>
#include <cerrno>
#include <cstring>

namespace mocap::outputs::osc {
namespace {
void put_be32(uint8_t* p, uint32_t v) {
  p[0] = static_cast<uint8_t>(v >> 24);
  p[1] = static_cast<uint8_t>(v >> 16);
  p[2] = static_cast<uint8_t>(v >> 8);
  p[3] = static_cast<uint8_t>(v);
}
}  // namespace

MessageWriter& MessageWriter::str(std::string_view s) {
  const std::size_t padded = (s.size() + 4) & ~std::size_t{3};  // at least one NUL
  if (!ok_ || cap_ - len_ < padded) {
    ok_ = false;
    return *this;
  }
  std::memcpy(out_ + len_, s.data(), s.size());
  std::memset(out_ + len_ + s.size(), 0, padded - s.size());
  len_ += padded;
  return *this;
}

MessageWriter& MessageWriter::i32(int32_t v) {
  if (!ok_ || cap_ - len_ < 4) {
    ok_ = false;
    return *this;
  }
  put_be32(out_ + len_, static_cast<uint32_t>(v));
  len_ += 4;
  return *this;
}

MessageWriter& MessageWriter::f32(float v) {
  if (!ok_ || cap_ - len_ < 4) {
    ok_ = false;
    return *this;
  }
  put_be32(out_ + len_, std::bit_cast<uint32_t>(v));
  len_ += 4;
  return *this;
}

void BundleWriter::begin(uint64_t timetag) {
  len_ = 0;
  count_ = 0;
  if (cap_ < 16) return;
  std::memcpy(out_, "#bundle\0", 8);
  put_be32(out_ + 8, static_cast<uint32_t>(timetag >> 32));
  put_be32(out_ + 12, static_cast<uint32_t>(timetag));
  len_ = 16;
}

bool BundleWriter::add(const uint8_t* message, std::size_t size) {
  if (len_ < 16 || size % 4 != 0 || cap_ - len_ < size + 4) return false;
  put_be32(out_ + len_, static_cast<uint32_t>(size));
  std::memcpy(out_ + len_ + 4, message, size);
  len_ += size + 4;
  ++count_;
  return true;
}

UdpTarget::~UdpTarget() {
  if (fd_ >= 0) ::close(fd_);
}

bool UdpTarget::open(const std::string& host, uint16_t port, std::string_view who,
                     std::string* error) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  if (inet_pton(AF_INET, host.c_str(), &a.sin_addr) != 1) {
    if (error) *error = std::string(who) + ": target address '" + host + "' is not an IPv4 address";
    return false;
  }
  static_assert(sizeof(sockaddr_in) <= sizeof addr_);
  std::memcpy(addr_, &a, sizeof a);
  if (fd_ >= 0) ::close(fd_);
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) {
    if (error) *error = std::string(who) + ": cannot create UDP socket: " + std::strerror(errno);
    return false;
  }
  return true;
}

bool UdpTarget::send(const void* data, std::size_t size) const noexcept {
  return fd_ >= 0 && ::sendto(fd_, data, size, MSG_DONTWAIT | MSG_NOSIGNAL,
                              reinterpret_cast<const sockaddr*>(addr_), sizeof(sockaddr_in)) >= 0;
}

}  // namespace mocap::outputs::osc
