// Hand-rolled OSC 1.0 encoding (big-endian, 4-byte aligned strings, bundles) into caller
// buffers with no allocation, and what the OSC senders (VMC, VRChat) share: the UDP target,
// their destination options, frame counters and frame-time rate limit. mocapd receives no OSC.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace mocap::outputs::osc {

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

/// Where an OSC sender sends and how often; DefaultPort is where its receivers listen.
template <uint16_t DefaultPort>
struct SenderOptions {
  std::string host = "127.0.0.1";  ///< IPv4 address of the receiver
  uint16_t port = DefaultPort;
  int min_interval_ms = 10;  ///< frames closer than this are skipped (<= 100 Hz)
};

/// The frame counters every OSC sender keeps.
struct FrameStats {
  uint64_t frames_sent = 0;
  uint64_t frames_rate_limited = 0;  ///< skipped by min_interval_ms
  uint64_t frames_invalid = 0;       ///< skipped: non-finite values
  uint64_t send_errors = 0;          ///< sendto failures (e.g. EAGAIN); what it carried is lost
};

/// What the OSC senders share at run time: the socket and the rate limit in frame time (a frame
/// closer than min_interval_ms after the last one sent is not due; one whose time went back, a
/// new replay, is).
class FrameTarget {
 public:
  /// (Re)opens the socket for the options' host:port and restarts the rate limit. False with
  /// "<who>: ..." in `error` for a bad address or socket.
  template <uint16_t DefaultPort>
  bool open(const SenderOptions<DefaultPort>& o, std::string_view who, std::string* error) {
    min_interval_ns_ = int64_t{o.min_interval_ms} * 1'000'000;
    sent_any_ = false;
    return udp_.open(o.host, o.port, who, error);
  }
  /// Whether a frame at t_ns goes out: not if the socket is not open, nor if it comes too soon
  /// (counted in stats.frames_rate_limited).
  bool due(int64_t t_ns, FrameStats& stats) noexcept {
    if (!udp_.is_open()) return false;
    if (!sent_any_ || t_ns < last_t_ns_ || t_ns - last_t_ns_ >= min_interval_ns_) return true;
    ++stats.frames_rate_limited;
    return false;
  }
  /// The frame at t_ns goes out (the next ones are limited from it).
  void sent(int64_t t_ns) noexcept {
    sent_any_ = true;
    last_t_ns_ = t_ns;
  }
  bool sent_any() const noexcept { return sent_any_; }
  /// Sends one datagram without blocking; false if it was not sent (lost).
  bool send(const void* data, std::size_t size) const noexcept { return udp_.send(data, size); }

 private:
  UdpTarget udp_;
  int64_t min_interval_ns_ = 0, last_t_ns_ = 0;
  bool sent_any_ = false;
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

}  // namespace mocap::outputs::osc
