// Session file codec: the header and the block payloads in explicit little-endian layout
// (docs/session-format.md). Every field is written one by one, never memcpy of a struct.
#include "mocap/session/format.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <type_traits>
#include "block_crc.hpp"

namespace mocap::session {
namespace {

/// Sequential little-endian writer over a caller buffer (sized by the caller).
struct Put {
  uint8_t* p;
  void u8(uint8_t v) { *p++ = v; }
  void u16(uint16_t v) { put_u16(p, v), p += 2; }
  void u32(uint32_t v) { put_u32(p, v), p += 4; }
  void u64(uint64_t v) { put_u64(p, v), p += 8; }
  void i64(int64_t v) { u64(static_cast<uint64_t>(v)); }
  void f32(float v) { u32(std::bit_cast<uint32_t>(v)); }
  void f64(double v) { u64(std::bit_cast<uint64_t>(v)); }
  void bytes(const void* d, std::size_t n) {
    if (n) std::memcpy(p, d, n);
    p += n;
  }
  /// Writes v in the width of its type (the same call shape as Get::field).
  template <typename T>
  void field(const T& v) {
    if constexpr (std::is_same_v<T, double>)
      f64(v);
    else if constexpr (std::is_same_v<T, float>)
      f32(v);
    else if constexpr (sizeof(T) == 1)
      u8(static_cast<uint8_t>(v));
    else if constexpr (sizeof(T) == 2)
      u16(static_cast<uint16_t>(v));
    else if constexpr (sizeof(T) == 4)
      u32(static_cast<uint32_t>(v));
    else
      u64(static_cast<uint64_t>(v));
  }
};

/// Sequential bounds-checked little-endian reader; any overrun sets ok = false. kChecked false:
/// no checks, for a payload whose size was checked against its fixed layout (a replay decodes
/// millions of samples).
template <bool kChecked>
struct GetBytes {
  const uint8_t* p;
  const uint8_t* end;
  bool ok = true;
  bool need(std::size_t n) {
    if constexpr (kChecked) {
      if (!ok || static_cast<std::size_t>(end - p) < n) ok = false;
    }
    return ok;
  }
  uint8_t u8() { return need(1) ? *p++ : 0; }
  uint16_t u16() {
    if (!need(2)) return 0;
    p += 2;
    return get_u16(p - 2);
  }
  uint32_t u32() {
    if (!need(4)) return 0;
    p += 4;
    return get_u32(p - 4);
  }
  uint64_t u64() {
    if (!need(8)) return 0;
    p += 8;
    return get_u64(p - 8);
  }
  int64_t i64() { return static_cast<int64_t>(u64()); }
  float f32() { return std::bit_cast<float>(u32()); }
  double f64() { return std::bit_cast<double>(u64()); }
  /// Reads v in the width of its type (the same call shape as Put::field).
  template <typename T>
  void field(T& v) {
    if constexpr (std::is_same_v<T, double>)
      v = f64();
    else if constexpr (std::is_same_v<T, float>)
      v = f32();
    else if constexpr (sizeof(T) == 1)
      v = static_cast<T>(u8());
    else if constexpr (sizeof(T) == 2)
      v = static_cast<T>(u16());
    else if constexpr (sizeof(T) == 4)
      v = static_cast<T>(u32());
    else
      v = static_cast<T>(u64());
  }
  bool str(std::string& s, std::size_t n) {
    if (!need(n)) return false;
    s.assign(reinterpret_cast<const char*>(p), n);
    p += n;
    return true;
  }
};

using Get = GetBytes<true>;

bool finite_all(const float* v, int n) {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(v[i])) return false;
  return true;
}

// One field list per record, walked by Put (encode, const record) and Get (decode): the layout
// is written once. docs/session-format.md gives the same order.

template <typename IO, typename Sample>
void sample_fields(IO& io, Sample& s) {
  io.field(s.t_host_ns);
  io.field(s.t_device_ns);
  io.field(s.seq);
  io.field(s.sensor_id);
  io.field(s.valid);
  io.field(s.flags);
  for (int i = 0; i < 3; ++i)
    io.field(s.gyr_rad_s[i]);
  for (int i = 0; i < 3; ++i)
    io.field(s.acc_m_s2[i]);
  for (int i = 0; i < 3; ++i)
    io.field(s.mag_uT[i]);
  io.field(s.q_device_sensor.w());
  io.field(s.q_device_sensor.x());
  io.field(s.q_device_sensor.y());
  io.field(s.q_device_sensor.z());
}

/// Segment s of a pose: orientation, position, joint rotation, violation, flags.
template <typename IO, typename Frame>
void segment_fields(IO& io, Frame& f, int s) {
  for (auto& v : f.q_earth_segment[s])
    io.field(v);
  for (auto& v : f.p_earth_segment_m[s])
    io.field(v);
  for (auto& v : f.q_parent_segment[s])
    io.field(v);
  io.field(f.joint_violation_deg[s]);
  io.field(f.segment_flags[s]);
}

/// A sensor status after its name bytes.
template <typename IO, typename Status>
void sensor_status_fields(IO& io, Status& st) {
  io.field(st.segment);
  io.field(st.state);
  io.field(st.flags);
  io.field(st.rate_hz);
  io.field(st.last_age_ms);
  io.field(st.drops);
  io.field(st.errors);
  io.field(st.gyro_bias_dps);
  io.field(st.heading_sigma_deg);
}

}  // namespace

bool encode_file_header(const SessionHeader& h, std::vector<uint8_t>& out, std::string* error) {
  auto fail = [&](const std::string& m) {
    if (error) *error = "session header: " + m;
    return false;
  };
  if (h.config_text.size() > kMaxTextBytes) return fail("config text longer than 1 MiB");
  if (h.calibration_text.size() > kMaxTextBytes) return fail("calibration text longer than 1 MiB");
  if (h.sensors.size() > kMaxSensorEntries) return fail("more than 256 sensors");
  std::size_t payload = 8 + 8 + 4 + h.config_text.size() + 4 + h.calibration_text.size() + 2;
  for (const auto& s : h.sensors) {
    if (s.name.size() > kMaxNameBytes || s.protocol.size() > kMaxNameBytes)
      return fail("sensor name or protocol '" + s.name.substr(0, 32) + "' longer than 255 bytes");
    if (s.segment < -1 || s.segment >= kSegmentCount)
      return fail("sensor '" + s.name + "' has segment index out of range");
    payload += 1 + s.name.size() + 1 + s.protocol.size() + 1 + 1 + 2;
  }
  out.assign(8 + 4 + 4 + 4 + payload + 4, 0);
  Put w{out.data()};
  w.bytes(kMagic, 8);
  w.u32(kVersion);
  w.u32(kEndianTag);
  w.u32(static_cast<uint32_t>(payload));
  w.i64(h.t_start_unix_ns);
  w.i64(h.t_start_host_ns);
  w.u32(static_cast<uint32_t>(h.config_text.size()));
  w.bytes(h.config_text.data(), h.config_text.size());
  w.u32(static_cast<uint32_t>(h.calibration_text.size()));
  w.bytes(h.calibration_text.data(), h.calibration_text.size());
  w.u16(static_cast<uint16_t>(h.sensors.size()));
  for (const auto& s : h.sensors) {
    w.u8(static_cast<uint8_t>(s.name.size()));
    w.bytes(s.name.data(), s.name.size());
    w.u8(static_cast<uint8_t>(s.protocol.size()));
    w.bytes(s.protocol.data(), s.protocol.size());
    w.u8(static_cast<uint8_t>(static_cast<int8_t>(s.segment)));
    w.u8(0);
    w.u16(s.device_index);
  }
  const auto crc = session::block_crc(0, out.data(), static_cast<std::size_t>(out.size() - 4));
  w.u32(static_cast<uint32_t>(crc));
  return true;
}

bool decode_header_payload(std::span<const uint8_t> payload, SessionHeader& h, std::string* error) {
  auto fail = [&](const std::string& m) {
    if (error) *error = "session header: " + m;
    return false;
  };
  Get r{payload.data(), payload.data() + payload.size()};
  h = SessionHeader{};
  h.t_start_unix_ns = r.i64();
  h.t_start_host_ns = r.i64();
  const uint32_t config_len = r.u32();
  if (config_len > kMaxTextBytes) return fail("config text length exceeds 1 MiB");
  if (!r.str(h.config_text, config_len)) return fail("config text truncated");
  const uint32_t calib_len = r.u32();
  if (calib_len > kMaxTextBytes) return fail("calibration text length exceeds 1 MiB");
  if (!r.str(h.calibration_text, calib_len)) return fail("calibration text truncated");
  const uint16_t n = r.u16();
  if (!r.ok) return fail("sensor count truncated");
  if (n > kMaxSensorEntries) return fail("sensor count " + std::to_string(n) + " exceeds 256");
  h.sensors.resize(n);
  for (auto& s : h.sensors) {
    if (!r.str(s.name, r.u8()) || !r.str(s.protocol, r.u8()))
      return fail("sensor description truncated");
    s.segment = static_cast<int8_t>(r.u8());
    r.u8();
    s.device_index = r.u16();
    if (!r.ok) return fail("sensor description truncated");
    if (s.segment < -1 || s.segment >= kSegmentCount)
      return fail("sensor '" + s.name + "' has segment index out of range");
  }
  if (r.p != r.end) return fail("unexpected bytes after the sensor list");
  return true;
}

void encode_sample(const ImuSample& s, uint8_t* out) noexcept {
  Put w{out};
  sample_fields(w, s);
}

bool decode_sample(std::span<const uint8_t> payload, ImuSample& s) noexcept {
  if (payload.size() != kSamplePayloadBytes) return false;  // the fields' fixed size
  GetBytes<false> r{payload.data(), payload.data() + payload.size()};
  sample_fields(r, s);
  return r.ok && s.gyr_rad_s.allFinite() && s.acc_m_s2.allFinite() && s.mag_uT.allFinite() &&
         s.q_device_sensor.coeffs().allFinite();
}

std::size_t encode_pose(const PoseFrame& f, uint8_t* out) noexcept {
  const uint32_t n = f.sensor_count < kMaxSensors ? f.sensor_count : kMaxSensors;
  Put w{out};
  w.u64(f.frame);
  w.i64(f.t_ns);
  w.u32(f.flags);
  w.u32(n);
  w.f32(f.calib_countdown_s);
  w.f32(0);  // reserved
  for (int s = 0; s < kSegmentCount; ++s)
    segment_fields(w, f, s);
  for (uint32_t i = 0; i < n; ++i) {
    const SensorStatus& st = f.sensors[i];
    w.bytes(st.name, sizeof st.name);
    sensor_status_fields(w, st);
  }
  return static_cast<std::size_t>(w.p - out);
}

bool decode_pose(std::span<const uint8_t> payload, PoseFrame& f) noexcept {
  if (payload.size() < kPoseFixedBytes) return false;
  Get r{payload.data(), payload.data() + payload.size()};
  f = PoseFrame{};
  f.frame = r.u64();
  f.t_ns = r.i64();
  f.flags = r.u32();
  f.sensor_count = r.u32();
  if (f.sensor_count > static_cast<uint32_t>(kMaxSensors) ||
      payload.size() != kPoseFixedBytes + kPoseSensorBytes * f.sensor_count)
    return false;
  f.calib_countdown_s = r.f32();
  r.f32();  // reserved
  for (int s = 0; s < kSegmentCount; ++s) {
    segment_fields(r, f, s);
    if (!finite_all(f.q_earth_segment[s].data(), 4) ||
        !finite_all(f.p_earth_segment_m[s].data(), 3) ||
        !finite_all(f.q_parent_segment[s].data(), 4) || !std::isfinite(f.joint_violation_deg[s]))
      return false;
  }
  for (uint32_t i = 0; i < f.sensor_count; ++i) {
    SensorStatus& st = f.sensors[i];
    if (!r.need(sizeof st.name)) return false;
    std::memcpy(st.name, r.p, sizeof st.name);
    st.name[sizeof st.name - 1] = '\0';
    r.p += sizeof st.name;
    sensor_status_fields(r, st);
  }
  return r.ok && std::isfinite(f.calib_countdown_s);
}

void encode_raw_prefix(uint16_t device_index, int64_t t_host_ns, uint8_t* out) noexcept {
  Put w{out};
  w.u16(device_index);
  w.u16(0);
  w.i64(t_host_ns);
}

void encode_block_header(BlockType type, uint32_t payload_len, uint8_t* out) noexcept {
  Put w{out};
  w.u16(kBlockSync);
  w.u8(static_cast<uint8_t>(type));
  w.u8(0);
  w.u32(payload_len);
}

void encode_header_copy_blocks(std::span<const uint8_t> file_header, std::vector<uint8_t>& out) {
  for (std::size_t off = 0; off < file_header.size(); off += kHeaderCopyChunk) {
    const std::size_t n = std::min(kHeaderCopyChunk, file_header.size() - off);
    const std::size_t start = out.size();
    out.resize(start + kBlockHeaderBytes + kHeaderCopyPrefixBytes + n + kBlockTrailerBytes);
    uint8_t* p = out.data() + start;
    encode_block_header(BlockType::header_copy, static_cast<uint32_t>(kHeaderCopyPrefixBytes + n),
                        p);
    put_u32(p + kBlockHeaderBytes, static_cast<uint32_t>(file_header.size()));
    put_u32(p + kBlockHeaderBytes + 4, static_cast<uint32_t>(off));
    std::memcpy(p + kBlockHeaderBytes + kHeaderCopyPrefixBytes, file_header.data() + off, n);
    const std::size_t body = kBlockHeaderBytes + kHeaderCopyPrefixBytes + n;
    put_u32(p + body,
            static_cast<uint32_t>(session::block_crc(0, p, static_cast<std::size_t>(body))));
  }
}

}  // namespace mocap::session
