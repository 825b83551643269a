// WitMotion WT901/JY901/HWT901B serial protocol (0x55 packets): the pure framer (bytes -> wire
// packets of raw int16), the configuration commands, and the wire encoder used by simulators.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace mocap::witmotion {

constexpr std::size_t kPacketSize = 11;
constexpr uint8_t kHeader = 0x55;
enum Type : uint8_t {
  kTime = 0x50,
  kAcc = 0x51,
  kGyr = 0x52,
  kAngle = 0x53,
  kMag = 0x54,
  kQuat = 0x59,
  kRegReply = 0x5F,
};
/// Registers written with FF AA <reg> <lo> <hi>.
enum Reg : uint8_t {
  kRegSave = 0x00,
  kRegCalib = 0x01,
  kRegRsw = 0x02,
  kRegRate = 0x03,
  kRegBaud = 0x04,
  kRegRead = 0x27,
  kRegKey = 0x69,
};
constexpr uint16_t kUnlockKey = 0xB588;

/// One packet as on the wire: type and four little-endian int16 words D0..D3.
struct Packet {
  uint8_t type = 0;
  std::array<int16_t, 4> d{};
};

/// Finds packets in a byte stream: header 0x55, a known type, checksum = sum of bytes 0..9.
/// On a bad checksum drops one byte and rescans (the vendor rule). Fixed buffer, no allocation.
class Framer {
 public:
  /// Consumes bytes from `in` until one packet is complete (got = true) or `in` is used up.
  /// Returns the number of bytes consumed.
  std::size_t consume(std::span<const uint8_t> in, Packet& out, bool& got);
  uint64_t frames = 0, checksum_errors = 0, resyncs = 0;

 private:
  void discard(std::size_t n);
  std::array<uint8_t, kPacketSize> buf_{};
  std::size_t n_ = 0;
  bool in_sync_ = true;
};

bool valid_type(uint8_t type);
/// Appends an 11-byte packet with its checksum.
void encode(const Packet& p, std::vector<uint8_t>& out);
/// A 5-byte configuration command FF AA reg lo hi.
std::array<uint8_t, 5> command(uint8_t reg, uint16_t value);

/// Return-rate register code for a rate in Hz (nearest supported; 0.2..200 Hz), and back.
uint8_t rate_code(double hz);
double rate_hz(uint8_t code);
/// Baud register code (0 if the baud is not supported), and back.
uint8_t baud_code(int baud);
int baud_from_code(uint8_t code);

/// Output-content (RSW) bit for a packet type: bit (type - 0x50).
constexpr uint16_t rsw_bit(uint8_t type) {
  return static_cast<uint16_t>(1u << (type - 0x50));
}

}  // namespace mocap::witmotion
