// The SlimeVR tracker UDP protocol ("extended owoTrack", firmware protocol 22), as read from
// SlimeVR-Tracker-ESP and SlimeVR-Server (../shared/reference/protocols.md section 6.6): the
// pure parser (one datagram -> wire packets, bundles expanded) and the writers of the packets
// a server sends. All fields big-endian. No units here beyond the wire's own.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace mocap::slimevr {

constexpr uint16_t kDefaultPort = 6969;

/// Packet types (u32 at the start of every tracker packet).
enum Type : uint32_t {
  kHeartbeat = 0,  ///< tracker -> server keep-alive (server -> tracker: kServerHeartbeat)
  kRotation = 1,   ///< legacy rotation: float x, y, z, w of sensor 0
  kHandshake = 3,
  kAccel = 4,  ///< float x, y, z (m/s^2, gravity removed), then the sensor id
  kPingPong = 10,
  kBattery = 12,
  kTap = 13,
  kError = 14,
  kSensorInfo = 15,
  kRotationData = 17,
  kMagAccuracy = 18,
  kSignalStrength = 19,
  kTemperature = 20,
  kUserAction = 21,
  kFeatureFlags = 22,
  kRotationAccel = 23,  ///< Q15 quaternion + acceleration / 128
  kBundle = 100,
  kCompactBundle = 101,
};
/// Server -> tracker heartbeat type.
constexpr uint32_t kServerHeartbeat = 1;

/// Packet 21 actions (the tracker's button or gesture), numbered as SlimeVR-Server's
/// UDPPacket21UserAction reads them.
enum UserAction : uint8_t {
  kResetFull = 2,
  kResetYaw = 3,
  kResetMounting = 4,
  kPauseTracking = 5,
};

/// Names of the handshake's board, IMU and MCU numbers (SlimeVR-Server's BoardType, IMUType,
/// MCUType; the HID receiver's device-info packet uses the same numbers); nullptr if unknown.
const char* board_name(uint32_t id);
const char* imu_name(uint32_t id);
const char* mcu_name(uint32_t id);

using Mac = std::array<uint8_t, 6>;

/// "AA:BB:CC:DD:EE:FF" (case-insensitive, ':' or '-'); false if malformed.
bool parse_mac(std::string_view text, Mac& mac);
std::string mac_string(const Mac& mac);

/// One packet of a datagram (a bundle gives several). Fields not carried by the type are 0.
struct Packet {
  uint32_t type = 0;
  uint64_t number = 0;      ///< packet number (0 inside bundles: they share the outer one)
  uint8_t sensor_id = 0;    ///< sensor on the board (types 4, 15, 17-20, 23; 0 for type 1)
  bool has_quat = false;    ///< quat_xyzw holds a rotation (types 1, 17, 23)
  bool has_accel = false;   ///< accel holds an acceleration (types 4, 23)
  float quat_xyzw[4] = {};  ///< as sent: x, y, z, w
  float accel[3] = {};      ///< m/s^2
  uint8_t data_type = 0;    ///< 17: 1 = normal rotation, 2 = correction
  uint8_t accuracy = 0;     ///< 17: calibration info
  int32_t ping_id = 0;      ///< 10
  float battery_v = 0, battery_level = 0;  ///< 12 (level 0..1; older firmware sends only it)
  uint8_t sensor_state = 0, imu_type = 0;  ///< 15
  float mag_accuracy = 0;                  ///< 18
  int8_t rssi_dbm = 0;                     ///< 19: WiFi signal strength (sensor id 255: board)
  float temperature_c = 0;                 ///< 20: the sensor's temperature
  uint8_t action = 0;                      ///< 21 (UserAction)
  uint8_t feature_flags = 0;               ///< 22: first flag byte
  // 3 handshake:
  uint32_t board = 0, mcu = 0, protocol_version = 0;
  uint32_t handshake_imu = 0;
  Mac mac{};
  bool has_mac = false;
  uint8_t firmware_len = 0;
  std::array<char, 64> firmware{};  ///< first firmware_len chars (truncated at 64)
  std::string_view firmware_text() const { return {firmware.data(), firmware_len}; }
};

/// Why a datagram (or part of it) was not taken.
enum class Error : uint8_t { kNone, kShort, kUnknownType, kBadBundle, kTooMany };
const char* error_text(Error e);

constexpr std::size_t kMaxPackets = 32;  ///< per datagram (bundles)

/// Parses one datagram into out (bundles expanded, in order). Returns the count; err tells why
/// parsing stopped early or what was skipped (an unknown type is skipped, the rest kept).
std::size_t parse_datagram(std::span<const uint8_t> datagram, std::span<Packet> out, Error& err);

// Writers of what a server sends; each returns the byte count written into out.
/// The handshake reply: 0x03, "Hey OVR =D 5", zero-padded to 64 bytes.
constexpr std::size_t kHandshakeReplySize = 64;
std::size_t write_handshake_reply(std::span<uint8_t, kHandshakeReplySize> out);
/// Server heartbeat (type 1, packet number): 12 bytes.
std::size_t write_heartbeat(std::span<uint8_t, 12> out, uint64_t number);
/// Ping (type 10, number, ping id): 16 bytes; the tracker echoes it.
std::size_t write_ping(std::span<uint8_t, 16> out, uint64_t number, int32_t ping_id);
/// Sensor-info acknowledgement: 00 00 00 0F id state (6 bytes, no packet number).
std::size_t write_sensor_info_ack(std::span<uint8_t, 6> out, uint8_t sensor_id, uint8_t state);
/// Server feature flags (type 22, number, flag byte): 13 bytes. Bit 0: bundles accepted.
std::size_t write_feature_flags(std::span<uint8_t, 13> out, uint64_t number, uint8_t flags);

}  // namespace mocap::slimevr
