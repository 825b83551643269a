// The SlimeVR USB HID receiver dongle (VID 0x1209, PID 0x7690; nRF "Smol Slime" trackers), as
// read from SlimeVR-Server's TrackersHID: each input report carries 16-byte packets
// [type][tracker id][14 data bytes], little-endian. The pure parser: report -> packets.
//   255 register: the receiver binds tracker id to the tracker's 48-bit address (bytes 2..7)
//   0 device info: battery, voltage, temperature, board, MCU, IMU (8), magnetometer (9),
//     firmware date and version, RSSI
//   1 quaternion Q15 x, y, z, w + acceleration Q7 (m/s^2, gravity removed)
//   2 quaternion as an exponential map in 10/11/11 bits + acceleration Q7, battery, RSSI
//   3 status (server status byte, RSSI)
//   4 quaternion Q15 + magnetometer Q10 (gauss)
//   5, 6, 7 (runtime, data, another reduced form in newer receivers): layouts not read, skipped
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace mocap::slimevr_hid {

constexpr uint16_t kVid = 0x1209, kReceiverPid = 0x7690;
constexpr std::size_t kPacketSize = 16;
constexpr std::size_t kMaxPackets = 8;  ///< per report (64-byte reports hold 4)

enum Type : uint8_t {
  kInfo = 0,
  kQuatAccel = 1,
  kCompactQuatAccel = 2,
  kStatus = 3,
  kQuatMag = 4,
  kRegister = 255,
};

struct Packet {
  uint8_t type = 0, id = 0;
  std::array<uint8_t, 6> address{};  ///< 255: the tracker's address (little-endian on the wire)
  bool has_quat = false, has_accel = false, has_mag = false;
  double quat_xyzw[4] = {0, 0, 0, 1};
  double accel_m_s2[3] = {};
  double mag_gauss[3] = {};
  uint8_t battery = 0, imu = 0, board = 0, mcu = 0, rssi = 0, status = 0;
};

/// The packets of one input report (a leading report-id byte is skipped when the size is not a
/// multiple of 16). Unknown types and zero padding (type 0 with id 0 and no data) are skipped;
/// returns the count.
std::size_t parse_report(std::span<const uint8_t> report, std::span<Packet> out);

/// One 16-byte packet; false for a type whose layout is not known.
bool parse_packet(std::span<const uint8_t, kPacketSize> bytes, Packet& p);

}  // namespace mocap::slimevr_hid
