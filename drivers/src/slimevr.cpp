// The SlimeVR UDP parser and server-packet writers (see slimevr.hpp): a bounds-checked
// big-endian cursor over one datagram; bundles (100, 101) expanded into their inner packets.
#include "mocap/drivers/slimevr.hpp"

#include <bit>
#include <cstdio>
#include <cstring>
#include <iterator>

namespace mocap::slimevr {
namespace {

/// Big-endian reader; any read past the end sets bad and returns 0.
struct Cursor {
  std::span<const uint8_t> b;
  std::size_t at = 0;
  bool bad = false;

  std::size_t left() const { return b.size() - at; }
  bool need(std::size_t n) {
    if (left() < n) bad = true;
    return !bad;
  }
  uint8_t u8() { return need(1) ? b[at++] : 0; }
  uint16_t u16() {
    if (!need(2)) return 0;
    const uint16_t v = static_cast<uint16_t>(b[at] << 8 | b[at + 1]);
    at += 2;
    return v;
  }
  uint32_t u32() {
    if (!need(4)) return 0;
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i)
      v = v << 8 | b[at++];
    return v;
  }
  uint64_t u64() {
    const uint64_t hi = u32();
    return hi << 32 | u32();
  }
  int16_t i16() { return static_cast<int16_t>(u16()); }
  float f32() { return std::bit_cast<float>(u32()); }
};

void put_u32(uint8_t* p, uint32_t v) {
  for (int i = 3; i >= 0; --i, v >>= 8)
    p[i] = static_cast<uint8_t>(v);
}
void put_u64(uint8_t* p, uint64_t v) {
  put_u32(p, static_cast<uint32_t>(v >> 32));
  put_u32(p + 4, static_cast<uint32_t>(v));
}

/// The payload of one packet of `type` (after type and number). False: too short.
bool parse_body(uint32_t type, Cursor& c, Packet& p) {
  p.type = type;
  switch (type) {
    case kHeartbeat:
    case kTap:
    case kError:
      break;  // nothing the driver uses
    case kSignalStrength:
      p.sensor_id = c.u8();
      p.rssi_dbm = static_cast<int8_t>(c.u8());
      break;
    case kTemperature:
      p.sensor_id = c.u8();
      p.temperature_c = c.f32();
      break;
    case kRotation:
      for (float& q : p.quat_xyzw)
        q = c.f32();
      p.has_quat = true;
      break;
    case kHandshake: {
      // Every field after the type is optional in old firmware; missing tails stay 0.
      if (c.left() >= 4) p.board = c.u32();
      if (c.left() >= 4) p.handshake_imu = c.u32();
      if (c.left() >= 4) p.mcu = c.u32();
      if (c.left() >= 12) c.at += 12;  // IMU info: three u32
      if (c.left() >= 4) p.protocol_version = c.u32();
      if (c.left() >= 1) {
        const uint8_t n = c.u8();
        const std::size_t take = std::min<std::size_t>(n, c.left());
        p.firmware_len = static_cast<uint8_t>(std::min<std::size_t>(take, p.firmware.size()));
        std::memcpy(p.firmware.data(), c.b.data() + c.at, p.firmware_len);
        c.at += take;
      }
      if (c.left() >= 6) {
        for (uint8_t& m : p.mac)
          m = c.u8();
        p.has_mac = true;
      }
      return true;  // further fields (tracker type, strings) are not needed
    }
    case kAccel:
      for (float& a : p.accel)
        a = c.f32();
      p.has_accel = true;
      if (c.left() >= 1) p.sensor_id = c.u8();  // absent in old firmware: sensor 0
      break;
    case kPingPong:
      p.ping_id = static_cast<int32_t>(c.u32());
      break;
    case kBattery:
      p.battery_v = c.f32();
      if (c.left() >= 4) {
        p.battery_level = c.f32();
      } else {
        p.battery_level = p.battery_v;  // old firmware: the level only
        p.battery_v = 0;
      }
      break;
    case kSensorInfo:
      p.sensor_id = c.u8();
      p.sensor_state = c.u8();
      if (c.left() >= 1) p.imu_type = c.u8();
      break;
    case kRotationData:
      p.sensor_id = c.u8();
      p.data_type = c.u8();
      for (float& q : p.quat_xyzw)
        q = c.f32();
      p.accuracy = c.u8();
      p.has_quat = true;
      break;
    case kMagAccuracy:
      p.sensor_id = c.u8();
      p.mag_accuracy = c.f32();
      break;
    case kUserAction:
      p.action = c.u8();
      break;
    case kFeatureFlags:
      if (c.left() >= 1) p.feature_flags = c.u8();
      break;
    case kRotationAccel:
      p.sensor_id = c.u8();
      for (float& q : p.quat_xyzw)
        q = static_cast<float>(c.i16()) / 32768.0f;
      for (float& a : p.accel)
        a = static_cast<float>(c.i16()) / 128.0f;
      p.has_quat = p.has_accel = true;
      break;
    default:
      return true;  // unknown: the caller reports it
  }
  return !c.bad;
}

bool known(uint32_t type) {
  switch (type) {
    case kHeartbeat:
    case kRotation:
    case kHandshake:
    case kAccel:
    case kPingPong:
    case kBattery:
    case kTap:
    case kError:
    case kSensorInfo:
    case kRotationData:
    case kMagAccuracy:
    case kSignalStrength:
    case kTemperature:
    case kUserAction:
    case kFeatureFlags:
    case kRotationAccel:
      return true;
    default:
      return false;
  }
}

}  // namespace

const char* board_name(uint32_t id) {
  static constexpr const char* kNames[] = {"unknown board",
                                           "SlimeVR Legacy",
                                           "SlimeVR Dev",
                                           "NodeMCU",
                                           "custom board",
                                           "WROOM32",
                                           "Wemos D1 Mini",
                                           "TTGO T-Base",
                                           "ESP-01",
                                           "SlimeVR",
                                           "Lolin C3 Mini",
                                           "Beetle ESP32-C3",
                                           "ESP32-C3 DevKitM-1",
                                           "owoTrack",
                                           "Wrangler Joy-Cons",
                                           "Sony mocopi",
                                           "Wemos Wroom-02 D1 Mini",
                                           "XIAO ESP32C3",
                                           "Haritora"};
  if (id < std::size(kNames)) return kNames[id];
  return id == 250 ? "prototype" : nullptr;
}

const char* imu_name(uint32_t id) {
  static constexpr const char* kNames[] = {"unknown IMU", "MPU-9250",  "MPU-6500",  "BNO080",
                                           "BNO085",      "BNO055",    "MPU-6050",  "BNO086",
                                           "BMI160",      "ICM-20948", "ICM-42688", "BMI270",
                                           "LSM6DS3TR-C", "LSM6DSV",   "LSM6DSO",   "LSM6DSR"};
  if (id < std::size(kNames)) return kNames[id];
  return id == 250 ? "prototype" : nullptr;
}

const char* mcu_name(uint32_t id) {
  static constexpr const char* kNames[] = {"unknown MCU",      "ESP8266",  "ESP32",
                                           "owoTrack Android", "Wrangler", "owoTrack iOS",
                                           "ESP32-C3",         "mocopi",   "Haritora"};
  if (id < std::size(kNames)) return kNames[id];
  return id == 250 ? "prototype" : nullptr;
}

bool parse_mac(std::string_view text, Mac& mac) {
  if (text.size() != 17) return false;
  for (std::size_t i = 0; i < 6; ++i) {
    unsigned v = 0;
    for (std::size_t k = 0; k < 2; ++k) {
      const char ch = text[i * 3 + k];
      const int d = ch >= '0' && ch <= '9'   ? ch - '0'
                    : ch >= 'a' && ch <= 'f' ? ch - 'a' + 10
                    : ch >= 'A' && ch <= 'F' ? ch - 'A' + 10
                                             : -1;
      if (d < 0) return false;
      v = v * 16 + static_cast<unsigned>(d);
    }
    if (i < 5 && text[i * 3 + 2] != ':' && text[i * 3 + 2] != '-') return false;
    mac[i] = static_cast<uint8_t>(v);
  }
  return true;
}

std::string mac_string(const Mac& m) {
  char s[18];
  std::snprintf(s, sizeof s, "%02X:%02X:%02X:%02X:%02X:%02X", m[0], m[1], m[2], m[3], m[4], m[5]);
  return s;
}

const char* error_text(Error e) {
  switch (e) {
    case Error::kNone:
      return "ok";
    case Error::kShort:
      return "packet shorter than its type's fields";
    case Error::kUnknownType:
      return "unknown packet type (skipped)";
    case Error::kBadBundle:
      return "bundle entry length beyond the datagram";
    case Error::kTooMany:
      return "more bundled packets than one datagram may carry";
  }
  return "?";
}

std::size_t parse_datagram(std::span<const uint8_t> datagram, std::span<Packet> out, Error& err) {
  err = Error::kNone;
  Cursor c{datagram};
  const uint32_t type = c.u32();
  const uint64_t number = c.u64();
  if (c.bad) {
    err = Error::kShort;
    return 0;
  }
  std::size_t n = 0;
  // One inner packet of a bundle: its bytes, its type.
  const auto inner = [&](uint32_t t, std::span<const uint8_t> body) {
    if (!known(t) || t == kBundle || t == kCompactBundle) {
      err = Error::kUnknownType;
      return;
    }
    if (n == out.size()) {
      err = Error::kTooMany;
      return;
    }
    Cursor ic{body};
    Packet& p = out[n];
    p = Packet{};
    if (parse_body(t, ic, p))
      ++n;
    else
      err = Error::kShort;
  };
  if (type == kBundle) {
    while (c.left() > 0) {
      const uint16_t len = c.u16();
      if (c.bad || len < 4 || len > c.left()) {
        err = Error::kBadBundle;
        break;
      }
      const auto entry = datagram.subspan(c.at, len);
      c.at += len;
      Cursor ec{entry};
      const uint32_t t = ec.u32();
      inner(t, entry.subspan(4));
    }
    return n;
  }
  if (type == kCompactBundle) {
    while (c.left() > 0) {
      const uint8_t len = c.u8();
      if (len < 1 || len > c.left()) {
        err = Error::kBadBundle;
        break;
      }
      const auto entry = datagram.subspan(c.at, len);
      c.at += len;
      inner(entry[0], entry.subspan(1));
    }
    return n;
  }
  if (!known(type)) {
    err = Error::kUnknownType;
    return 0;
  }
  if (out.empty()) {
    err = Error::kTooMany;
    return 0;
  }
  Packet& p = out[0];
  p = Packet{};
  p.number = number;
  if (!parse_body(type, c, p)) {
    err = Error::kShort;
    return 0;
  }
  return 1;
}

std::size_t write_handshake_reply(std::span<uint8_t, kHandshakeReplySize> out) {
  static constexpr char kText[] = "Hey OVR =D 5";
  std::memset(out.data(), 0, out.size());
  out[0] = kHandshake;
  std::memcpy(out.data() + 1, kText, sizeof kText - 1);
  return out.size();
}

std::size_t write_heartbeat(std::span<uint8_t, 12> out, uint64_t number) {
  put_u32(out.data(), kServerHeartbeat);
  put_u64(out.data() + 4, number);
  return 12;
}

std::size_t write_ping(std::span<uint8_t, 16> out, uint64_t number, int32_t ping_id) {
  put_u32(out.data(), kPingPong);
  put_u64(out.data() + 4, number);
  put_u32(out.data() + 12, static_cast<uint32_t>(ping_id));
  return 16;
}

std::size_t write_sensor_info_ack(std::span<uint8_t, 6> out, uint8_t sensor_id, uint8_t state) {
  put_u32(out.data(), kSensorInfo);
  out[4] = sensor_id;
  out[5] = state;
  return 6;
}

std::size_t write_feature_flags(std::span<uint8_t, 13> out, uint64_t number, uint8_t flags) {
  put_u32(out.data(), kFeatureFlags);
  put_u64(out.data() + 4, number);
  out[12] = flags;
  return 13;
}

}  // namespace mocap::slimevr
