// Hand-rolled OSC 1.0 encoding (big-endian, 4-byte aligned strings, bundles) into caller
// buffers: what the VMC sender needs, with no allocation. Encoding only; mocapd receives no OSC.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace mocap::daemon::osc {

/// A non-blocking UDP socket aimed at one IPv4 host:port: the OSC senders' transport (VMC,
/// VRChat).
class UdpTarget {
 public:
  UdpTarget() = default;
  ~UdpTarget();
  UdpTarget(const UdpTarget&) = delete;
  UdpTarget& operator=(const UdpTarget&) = delete;
  /// (Re)opens the socket. False with "<who>: ..." in `error` for a bad address or socket.
  bool open(const std::string& host, uint16_t port, std::string_view who, std::string* error);
  bool is_open() const { return fd_ >= 0; }
  /// Sends one datagram without blocking; false if it was not sent (lost).
  bool send(const void* data, std::size_t size) const noexcept;

 private:
  int fd_ = -1;
  unsigned char addr_[16] = {};  // sockaddr_in
};

/// Timetag meaning "immediately" (OSC 1.0).
inline constexpr uint64_t kImmediate = 1;

/// Writes one OSC message into a fixed buffer. Call address(), then tags() (",sff..."), then
/// the arguments in tag order. ok() is false if anything did not fit.
class MessageWriter {
 public:
  MessageWriter(uint8_t* out, std::size_t capacity) : out_(out), cap_(capacity) {}
  MessageWriter& address(std::string_view a) { return str(a); }
  MessageWriter& tags(std::string_view t) { return str(t); }
  MessageWriter& str(std::string_view s);  ///< OSC-string: bytes, NUL, pad to 4
  MessageWriter& i32(int32_t v);
  MessageWriter& f32(float v);
  std::size_t size() const { return len_; }
  bool ok() const { return ok_; }

 private:
  uint8_t* out_;
  std::size_t cap_;
  std::size_t len_ = 0;
  bool ok_ = true;
};

/// Builds one OSC bundle ("#bundle", timetag, size-prefixed elements) in a fixed buffer.
class BundleWriter {
 public:
  BundleWriter(uint8_t* out, std::size_t capacity) : out_(out), cap_(capacity) {}
  /// Starts a new, empty bundle (discards the previous content).
  void begin(uint64_t timetag = kImmediate);
  /// Appends a message; false (bundle unchanged) if it would exceed the capacity.
  bool add(const uint8_t* message, std::size_t size);
  std::size_t size() const { return len_; }
  bool empty() const { return count_ == 0; }
  const uint8_t* data() const { return out_; }

 private:
  uint8_t* out_;
  std::size_t cap_;
  std::size_t len_ = 0;
  int count_ = 0;
};

}  // namespace mocap::daemon::osc
