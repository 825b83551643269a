// Xsens MTi Xbus protocol: the pure framer (FA FF MID LEN [EXTLEN] DATA CS), the MTData2 payload
// parser (big-endian floats and fixed point), and the message encoder used by the driver's
// configuration commands and by the simulated MTi.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace mocap::xbus {

constexpr uint8_t kPreamble = 0xFA;
constexpr uint8_t kBusMaster = 0xFF;
constexpr std::size_t kMaxPayload = 2048;

enum Mid : uint8_t {
  kReqDid = 0x00,
  kDeviceId = 0x01,
  kGoToMeasurement = 0x10,
  kGoToMeasurementAck = 0x11,
  kGoToConfig = 0x30,
  kGoToConfigAck = 0x31,
  kMtData2 = 0x36,
  kWakeUp = 0x3E,
  kWakeUpAck = 0x3F,
  kError = 0x42,
  kSetOutputConfig = 0xC0,
  kOutputConfigAck = 0xC1,
};
enum DataId : uint16_t {
  kPacketCounter = 0x1020,
  kSampleTimeFine = 0x1060,
  kQuaternion = 0x2010,
  kAcceleration = 0x4020,
  kRateOfTurn = 0x8020,
  kMagneticField = 0xC020,
};

/// One message; data points into the framer's buffer and is valid until the next consume().
struct Message {
  uint8_t bid = 0, mid = 0;
  std::span<const uint8_t> data;
};

/// Buffers bytes and extracts checksum-verified messages; skips garbage to the next preamble.
class Framer {
 public:
  /// Takes bytes from `in` (possibly none) and extracts at most one message. Call again with
  /// the rest (or an empty span) while got is true: several messages may be buffered.
  std::size_t consume(std::span<const uint8_t> in, Message& out, bool& got);
  uint64_t frames = 0, checksum_errors = 0, resyncs = 0;

 private:
  void drop(std::size_t k);
  std::array<uint8_t, 6 + kMaxPayload + 1> buf_{};
  std::size_t n_ = 0, front_ = 0;
  bool in_sync_ = true;
};

/// The MTData2 fields the drivers use, as sent (device frame, device units).
struct MtData2 {
  bool has_counter = false, has_time = false, has_acc = false, has_gyr = false, has_mag = false,
       has_quat = false;
  uint16_t counter = 0;
  uint32_t time_fine = 0;  ///< 10 kHz ticks
  std::array<double, 3> acc{}, gyr{}, mag{};
  std::array<double, 4> quat{};  ///< w, x, y, z
  uint8_t quat_coord = 0;        ///< 0 ENU, 4 NED, 8 NWU
};
/// Parses an MTData2 payload; false if a packet overruns the payload or has a bad size.
bool parse_mtdata2(std::span<const uint8_t> payload, MtData2& out);

/// Appends a complete message (preamble, bus id 0xFF, checksum; extended length if > 254).
void encode(uint8_t mid, std::span<const uint8_t> payload, std::vector<uint8_t>& out);
/// Appends one MTData2 packet header + float32 values (big-endian).
void put_floats(uint16_t id, std::span<const double> v, std::vector<uint8_t>& payload);

}  // namespace mocap::xbus
