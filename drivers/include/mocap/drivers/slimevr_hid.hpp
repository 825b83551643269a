// The SlimeVR USB HID receiver dongle (VID 0x1209, PID 0x7690; nRF "Smol Slime" trackers), as
// read from SlimeVR-Server's HIDCommon and written by SlimeVR-Tracker-nRF (connection.c) and its
// receiver (hid.c): each input report carries 16-byte packets [type][tracker id][14 data
// bytes], little-endian. The receiver writes its own RSSI magnitude into byte 15 of every
// tracker packet but types 1 and 4 (no room). The pure parser: report -> packets, in units.
//   255 register: the receiver binds tracker id to the tracker's 48-bit address (bytes 2..7)
//   0 device info: battery, voltage, temperature, board, MCU, -, IMU, magnetometer status,
//     firmware date (u16) and version (3 x u8), RSSI
//   1 quaternion Q15 x, y, z, w + acceleration Q7 (m/s^2, gravity removed)
//   2 battery, voltage, temperature, quaternion as an exponential map in 10/11/11 bits (u32),
//     acceleration Q7, RSSI
//   3 status: server status, tracker status, packets received, lost, windows hit, missed
//     (counted by the receiver), ..., RSSI
//   4 quaternion Q15 + magnetometer Q10 (gauss)
//   5 runtime: i64 microseconds of battery left (-1: not known yet), RSSI
//   6 button + sleep time: button action byte, u16 ms until the tracker sleeps, RSSI
//   7 button + sleep time + the reduced quaternion and acceleration of type 2, RSSI
// Field encodings: battery byte 0 = no battery, bit 7 = has one, 0x80 exactly = level unknown,
// else its low 7 bits are percent; voltage (byte + 245) / 100 V, 0 = none; temperature byte / 2
// - 39 degC, 0 = none; RSSI byte b is -b dBm, 0 = none.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
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
  kRuntime = 5,
  kButton = 6,
  kButtonQuatAccel = 7,
  kRegister = 255,
};

struct Packet {
  static constexpr float kUnknown = std::numeric_limits<float>::quiet_NaN();
  uint8_t type = 0, id = 0;
  std::array<uint8_t, 6> address{};  ///< 255: the tracker's address (little-endian on the wire)
  bool has_quat = false, has_accel = false, has_mag = false;
  double quat_xyzw[4] = {0, 0, 0, 1};
  double accel_m_s2[3] = {};
  double mag_gauss[3] = {};
  // Device info (0):
  uint8_t board = 0, mcu = 0, imu = 0, mag = 0;  ///< SlimeVR's BoardType, MCUType, IMUType ids
  bool has_firmware = false;
  uint16_t fw_year = 0;
  uint8_t fw_month = 0, fw_day = 0, fw_major = 0, fw_minor = 0, fw_patch = 0;
  // Battery and temperature (0, 2): unknown = NaN.
  float battery_fraction = kUnknown;  ///< 0..1
  float battery_v = kUnknown;
  float temperature_c = kUnknown;
  float rssi_dbm = kUnknown;  ///< every type but 1, 4 and 255 (the receiver's measurement)
  // Status (3):
  uint8_t status = 0, tracker_status = 0;
  bool has_link_counts = false;
  uint8_t packets_received = 0, packets_lost = 0, windows_hit = 0, windows_missed = 0;
  // Runtime (5): battery time left, us; -1 not known yet.
  int64_t runtime_us = -1;
  // Button and sleep time (6, 7):
  bool has_button = false;
  uint8_t button = 0;     ///< low 2 bits: 0 none, 1 single press, 2 double press
  uint16_t sleep_ms = 0;  ///< until the tracker sleeps (1: shutting down)
};

/// The packets of one input report (a leading report-id byte is skipped when the size is not a
/// multiple of 16). Unknown types and zero padding (type 0 with id 0 and no data) are skipped;
/// returns the count.
std::size_t parse_report(std::span<const uint8_t> report, std::span<Packet> out);

/// One 16-byte packet; false for a type whose layout is not known.
bool parse_packet(std::span<const uint8_t, kPacketSize> bytes, Packet& p);

}  // namespace mocap::slimevr_hid
