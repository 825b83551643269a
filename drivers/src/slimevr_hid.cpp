// SlimeVR HID receiver packets (see slimevr_hid.hpp): fixed 16-byte layouts, little-endian.
#include "mocap/drivers/slimevr_hid.hpp"

#include <cmath>
#include <numbers>

namespace mocap::slimevr_hid {
namespace {

int16_t i16(std::span<const uint8_t, kPacketSize> b, std::size_t at) {
  return static_cast<int16_t>(b[at] | b[at + 1] << 8);
}

void q15_quat(std::span<const uint8_t, kPacketSize> b, Packet& p) {
  for (std::size_t j = 0; j < 4; ++j)
    p.quat_xyzw[j] = i16(b, 2 + 2 * j) / 32768.0;
  p.has_quat = true;
}

void q7_accel(std::span<const uint8_t, kPacketSize> b, std::size_t at, Packet& p) {
  for (std::size_t j = 0; j < 3; ++j)
    p.accel_m_s2[j] = i16(b, at + 2 * j) / 128.0;
  p.has_accel = true;
}

}  // namespace

bool parse_packet(std::span<const uint8_t, kPacketSize> b, Packet& p) {
  p = Packet{};
  p.type = b[0];
  p.id = b[1];
  switch (p.type) {
    case kRegister:
      for (std::size_t j = 0; j < 6; ++j)
        p.address[j] = b[2 + j];
      return true;
    case kInfo:
      p.battery = b[2];
      p.board = b[5];
      p.mcu = b[6];
      p.imu = b[8];
      p.rssi = b[15];
      return true;
    case kQuatAccel:
      q15_quat(b, p);
      q7_accel(b, 10, p);
      return true;
    case kCompactQuatAccel: {
      p.battery = b[2];
      const uint32_t q = static_cast<uint32_t>(b[5]) | static_cast<uint32_t>(b[6]) << 8 |
                         static_cast<uint32_t>(b[7]) << 16 | static_cast<uint32_t>(b[8]) << 24;
      // Exponential map quantised to 10/11/11 bits, each in [-1, 1).
      const double v[3] = {(q & 1023u) / 1024.0 * 2 - 1, (q >> 10 & 2047u) / 2048.0 * 2 - 1,
                           (q >> 21 & 2047u) / 2048.0 * 2 - 1};
      const double d = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
      const double inv = 1 / std::sqrt(d + 1e-6);
      const double a = std::numbers::pi / 2 * d * inv;
      const double k = std::sin(a) * inv;
      p.quat_xyzw[0] = k * v[0];
      p.quat_xyzw[1] = k * v[1];
      p.quat_xyzw[2] = k * v[2];
      p.quat_xyzw[3] = std::cos(a);
      p.has_quat = true;
      q7_accel(b, 9, p);
      p.rssi = b[15];
      return true;
    }
    case kStatus:
      p.status = b[2];
      p.rssi = b[15];
      return true;
    case kQuatMag:
      q15_quat(b, p);
      for (std::size_t j = 0; j < 3; ++j)
        p.mag_gauss[j] = i16(b, 10 + 2 * j) / 1024.0;
      p.has_mag = true;
      return true;
    default:
      return false;
  }
}

std::size_t parse_report(std::span<const uint8_t> report, std::span<Packet> out) {
  if (report.size() % kPacketSize != 0 && report.size() > kPacketSize) report = report.subspan(1);
  std::size_t n = 0;
  for (std::size_t at = 0; at + kPacketSize <= report.size() && n < out.size(); at += kPacketSize) {
    const std::span<const uint8_t, kPacketSize> b(report.data() + at, kPacketSize);
    bool empty = true;
    for (const uint8_t x : b)
      empty = empty && x == 0;
    if (empty) continue;  // padding of a report with fewer packets
    if (parse_packet(b, out[n])) ++n;
  }
  return n;
}

}  // namespace mocap::slimevr_hid
