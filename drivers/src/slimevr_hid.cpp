// SlimeVR HID receiver packets (see slimevr_hid.hpp): fixed 16-byte layouts, little-endian.
#include "mocap/drivers/slimevr_hid.hpp"

#include <algorithm>
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

/// The exponential map quantised to 10/11/11 bits (u32 at byte 5), each in [-1, 1), back to a
/// quaternion.
void compact_quat(std::span<const uint8_t, kPacketSize> b, Packet& p) {
  const uint32_t q = static_cast<uint32_t>(b[5]) | static_cast<uint32_t>(b[6]) << 8 |
                     static_cast<uint32_t>(b[7]) << 16 | static_cast<uint32_t>(b[8]) << 24;
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
}

/// Battery, voltage and temperature bytes at `at` (types 0 and 2).
void battery_temperature(std::span<const uint8_t, kPacketSize> b, std::size_t at, Packet& p) {
  const uint8_t level = b[at], volts = b[at + 1], temp = b[at + 2];
  if (level != 0 && level != 0x80)  // 0: no battery; 0x80: has one, level not known yet
    p.battery_fraction = static_cast<float>(std::min(level & 127, 100)) / 100.0f;
  if (volts != 0) p.battery_v = static_cast<float>(volts + 245) / 100.0f;
  if (temp != 0) p.temperature_c = static_cast<float>(temp) / 2.0f - 39.0f;
}

void button_sleep(std::span<const uint8_t, kPacketSize> b, Packet& p) {
  p.has_button = true;
  p.button = b[2];
  p.sleep_ms = static_cast<uint16_t>(b[3] | b[4] << 8);
}

}  // namespace

bool parse_packet(std::span<const uint8_t, kPacketSize> b, Packet& p) {
  p = Packet{};
  p.type = b[0];
  p.id = b[1];
  if (p.type != kQuatAccel && p.type != kQuatMag && p.type != kRegister && b[15] != 0)
    p.rssi_dbm = -static_cast<float>(b[15]);
  switch (p.type) {
    case kRegister:
      for (std::size_t j = 0; j < 6; ++j)
        p.address[j] = b[2 + j];
      return true;
    case kInfo: {
      battery_temperature(b, 2, p);
      p.board = b[5];
      p.mcu = b[6];
      p.imu = b[8];
      p.mag = b[9];
      const unsigned date = b[10] | b[11] << 8;  // (year - 2020) << 9 | month << 5 | day
      p.has_firmware = true;
      p.fw_year = static_cast<uint16_t>(2020 + (date >> 9 & 127));
      p.fw_month = static_cast<uint8_t>(date >> 5 & 15);
      p.fw_day = static_cast<uint8_t>(date & 31);
      p.fw_major = b[12];
      p.fw_minor = b[13];
      p.fw_patch = b[14];
      return true;
    }
    case kQuatAccel:
      q15_quat(b, p);
      q7_accel(b, 10, p);
      return true;
    case kCompactQuatAccel:
      battery_temperature(b, 2, p);
      compact_quat(b, p);
      q7_accel(b, 9, p);
      return true;
    case kStatus:
      p.status = b[2];
      p.tracker_status = b[3];
      p.has_link_counts = true;
      p.packets_received = b[4];
      p.packets_lost = b[5];
      p.windows_hit = b[6];
      p.windows_missed = b[7];
      return true;
    case kQuatMag:
      q15_quat(b, p);
      for (std::size_t j = 0; j < 3; ++j)
        p.mag_gauss[j] = i16(b, 10 + 2 * j) / 1024.0;
      p.has_mag = true;
      return true;
    case kRuntime: {
      uint64_t u = 0;
      for (std::size_t j = 0; j < 8; ++j)
        u |= static_cast<uint64_t>(b[2 + j]) << (8 * j);
      p.runtime_us = static_cast<int64_t>(u);
      return true;
    }
    case kButton:
      button_sleep(b, p);
      return true;
    case kButtonQuatAccel:
      button_sleep(b, p);
      compact_quat(b, p);
      q7_accel(b, 9, p);
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
