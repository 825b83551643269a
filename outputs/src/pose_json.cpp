// format_pose_json: one PoseFrame as one line of JSON (schema v1, docs/streaming.md), written
// into a caller-supplied buffer with std::to_chars; no allocation, non-finite numbers as null.
#include <charconv>
#include <cmath>
#include <cstring>
#include <string_view>

#include "mocap/core/fixed_chars.hpp"
#include "mocap/outputs/pose_json.hpp"

namespace mocap::outputs {
namespace {

/// Length of the well-formed UTF-8 sequence (RFC 3629: no overlong form, surrogate or code
/// point beyond U+10FFFF) starting at s, within n bytes; 0 if there is none.
std::size_t utf8_sequence(const char* s, std::size_t n) {
  const auto b = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
  const unsigned char c = b(0);
  std::size_t len = 0;
  unsigned char lo = 0x80, hi = 0xBF;  // the range of the second byte
  if (c >= 0xC2 && c <= 0xDF) {
    len = 2;
  } else if (c >= 0xE0 && c <= 0xEF) {
    len = 3;
    if (c == 0xE0) lo = 0xA0;
    if (c == 0xED) hi = 0x9F;
  } else if (c >= 0xF0 && c <= 0xF4) {
    len = 4;
    if (c == 0xF0) lo = 0x90;
    if (c == 0xF4) hi = 0x8F;
  } else {
    return 0;
  }
  if (len > n) return 0;
  if (b(1) < lo || b(1) > hi) return 0;
  for (std::size_t k = 2; k < len; ++k)
    if (b(k) < 0x80 || b(k) > 0xBF) return 0;
  return len;
}

class LineOut {
 public:
  LineOut(char* begin, std::size_t cap) : p_(begin), end_(begin + cap) {}
  void put(char c) {
    if (p_ < end_)
      *p_++ = c;
    else
      ok_ = false;
  }
  void put(std::string_view s) {
    if (static_cast<std::size_t>(end_ - p_) < s.size()) {
      ok_ = false;
      p_ = end_;
      return;
    }
    std::memcpy(p_, s.data(), s.size());
    p_ += s.size();
  }
  void num(double v, int decimals) {
    if (!std::isfinite(v)) return put("null");
    auto r = to_chars_fixed(p_, end_, v, decimals);
    if (r.ec != std::errc()) {
      ok_ = false;
      p_ = end_;
      return;
    }
    p_ = r.ptr;
  }
  template <typename Int>
  void integer(Int v) {
    auto r = std::to_chars(p_, end_, v);
    if (r.ec != std::errc()) {
      ok_ = false;
      p_ = end_;
      return;
    }
    p_ = r.ptr;
  }
  /// A JSON string from at most max_len bytes (stops at NUL). Control characters are escaped;
  /// well-formed UTF-8 sequences (a sensor named "Jos\u00e9") are copied, any other byte outside
  /// ASCII becomes '?', so the line stays valid UTF-8 whatever a device reported.
  void str(const char* s, std::size_t max_len) {
    put('"');
    for (std::size_t i = 0; i < max_len && s[i] != '\0'; ++i) {
      const auto c = static_cast<unsigned char>(s[i]);
      if (c == '"' || c == '\\') {
        put('\\');
        put(static_cast<char>(c));
      } else if (c < 0x20) {
        static constexpr char kHex[] = "0123456789abcdef";
        put("\\u00");
        put(kHex[c >> 4]);
        put(kHex[c & 15]);
      } else if (c >= 0x80) {
        const std::size_t n = utf8_sequence(s + i, max_len - i);
        if (n == 0) {
          put('?');
        } else {
          put(std::string_view(s + i, n));
          i += n - 1;
        }
      } else {
        put(static_cast<char>(c));
      }
    }
    put('"');
  }
  template <std::size_t N>
  void array(const std::array<float, N>& a, int decimals) {
    put('[');
    for (std::size_t i = 0; i < N; ++i) {
      if (i) put(',');
      num(a[i], decimals);
    }
    put(']');
  }
  bool ok() const { return ok_; }
  char* pos() const { return p_; }

 private:
  char* p_;
  char* end_;
  bool ok_ = true;
};

}  // namespace

std::size_t format_pose_json(const PoseFrame& f, char* out, std::size_t capacity) noexcept {
  LineOut o(out, capacity);
  o.put("{\"v\":");
  o.integer(kPoseJsonVersion);
  o.put(",\"frame\":");
  o.integer(f.frame);
  o.put(",\"t\":");
  o.num(static_cast<double>(f.t_ns) * 1e-9, 6);
  o.put(",\"t_ns\":");
  o.integer(f.t_ns);
  o.put(",\"t_unix_ns\":");
  if (f.t_unix_ns != 0)
    o.integer(f.t_unix_ns);
  else
    o.put("null");
  o.put(",\"flags\":");
  o.integer(f.flags);
  o.put(",\"segments\":[");
  for (int s = 0; s < kSegmentCount; ++s) {
    if (s) o.put(',');
    o.put("{\"name\":\"");
    o.put(kSegmentNames[s]);
    o.put("\",\"q\":");
    o.array(f.q_earth_segment[s], 5);
    o.put(",\"p\":");
    o.array(f.p_earth_segment_m[s], 4);
    o.put(",\"flags\":");
    o.integer(f.segment_flags[s]);
    o.put('}');
  }
  o.put("],\"joints\":[");
  for (int s = 1; s < kSegmentCount; ++s) {
    if (s > 1) o.put(',');
    o.put("{\"name\":\"");
    o.put(kSegmentNames[s]);
    o.put("\",\"q\":");
    o.array(f.q_parent_segment[s], 5);
    o.put(",\"violation_deg\":");
    o.num(f.joint_violation_deg[s], 2);
    o.put('}');
  }
  o.put("],\"sensors\":[");
  const uint32_t n = f.sensor_count < kMaxSensors ? f.sensor_count : kMaxSensors;
  for (uint32_t i = 0; i < n; ++i) {
    const SensorStatus& st = f.sensors[i];
    if (i) o.put(',');
    o.put("{\"name\":");
    o.str(st.name, sizeof(st.name));
    o.put(",\"segment\":");
    if (st.segment >= 0 && st.segment < kSegmentCount) {
      o.put('"');
      o.put(kSegmentNames[st.segment]);
      o.put('"');
    } else {
      o.put("null");
    }
    o.put(",\"state\":");
    o.integer(static_cast<int>(st.state));
    o.put(",\"rate_hz\":");
    o.num(st.rate_hz, 1);
    o.put(",\"age_ms\":");
    o.num(st.last_age_ms, 1);
    o.put(",\"drops\":");
    o.integer(st.drops);
    o.put(",\"errors\":");
    o.integer(st.errors);
    o.put(",\"flags\":");
    o.integer(static_cast<int>(st.flags));
    o.put(",\"seq\":");
    o.integer(st.seq);
    o.put(",\"t_device_ns\":");
    o.integer(st.t_device_ns);
    o.put('}');
  }
  o.put("]}\n");
  if (!o.ok()) return 0;
  return static_cast<std::size_t>(o.pos() - out);
}

}  // namespace mocap::outputs
