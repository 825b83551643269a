// Pose JSON line -> PoseFrame, with validation of every field the viewer uses.
#include "mocap/viewer/pose_json.hpp"

#include <cmath>
#include <cstring>
#include <nlohmann/json.hpp>

namespace mocap::viewer {
namespace {

using json = nlohmann::json;

template <size_t N>
bool numbers(const json& j, std::array<float, N>& out) {
  if (!j.is_array() || j.size() != N) return false;
  for (size_t i = 0; i < N; ++i) {
    if (!j[i].is_number()) return false;  // null stands for a non-finite value
    const double v = j[i].get<double>();
    if (!std::isfinite(v) || std::abs(v) > 1e6) return false;
    out[i] = static_cast<float>(v);
  }
  return true;
}

bool unit_quaternion(const json& j, std::array<float, 4>& q) {
  if (!numbers(j, q)) return false;
  const float n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (!(n > 0.5f && n < 1.5f)) return false;
  for (float& v : q)
    v /= n;
  return true;
}

template <typename T>
bool integer(const json& j, const char* key, T& out) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_number_integer()) return false;
  const auto v = it->get<int64_t>();
  if (v < static_cast<int64_t>(std::numeric_limits<T>::min()) ||
      static_cast<uint64_t>(v) > static_cast<uint64_t>(std::numeric_limits<T>::max()))
    return false;
  out = static_cast<T>(v);
  return true;
}

float number_or(const json& j, const char* key, float fallback) {
  const auto it = j.find(key);
  if (it == j.end() || !it->is_number()) return fallback;
  const double v = it->get<double>();
  return std::isfinite(v) ? static_cast<float>(v) : fallback;
}

bool fail(std::string& error, std::string message) {
  error = std::move(message);
  return false;
}

}  // namespace

bool parse_pose_json(std::string_view line, PoseFrame& out, std::string& error) {
  if (line.size() > kMaxPoseJsonLine) return fail(error, "line too long");
  const json j = json::parse(line, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return fail(error, "not a JSON object");
  int v = 0;
  if (!integer(j, "v", v)) return fail(error, "missing schema version \"v\"");
  if (v != 1) return fail(error, "unknown schema version " + std::to_string(v));

  PoseFrame f;
  reset_pose(f);
  if (!integer(j, "frame", f.frame)) return fail(error, "missing or bad \"frame\"");
  if (!integer(j, "flags", f.flags)) return fail(error, "missing or bad \"flags\"");
  const auto t = j.find("t");
  if (t == j.end() || !t->is_number() || !std::isfinite(t->get<double>()))
    return fail(error, "missing or bad \"t\"");
  f.t_ns = static_cast<int64_t>(std::clamp(t->get<double>(), -9e9, 9e9) * 1e9);

  const auto segs = j.find("segments");
  if (segs == j.end() || !segs->is_array() || segs->size() != kSegmentCount)
    return fail(error, "\"segments\" must hold 16 entries");
  for (int s = 0; s < kSegmentCount; ++s) {
    const json& e = (*segs)[static_cast<size_t>(s)];
    const std::string where = "segment " + std::to_string(s);
    if (!e.is_object()) return fail(error, where + " is not an object");
    const auto n = e.find("name");
    if (n == e.end() || !n->is_string() || n->get<std::string>() != kSegmentNames[s])
      return fail(error, where + " must be named " + std::string(kSegmentNames[s]));
    if (!e.contains("q") || !unit_quaternion(e["q"], f.q_earth_segment[s]))
      return fail(error, where + " (" + std::string(kSegmentNames[s]) + "): bad quaternion \"q\"");
    if (!e.contains("p") || !numbers(e["p"], f.p_earth_segment_m[s]))
      return fail(error, where + " (" + std::string(kSegmentNames[s]) + "): bad position \"p\"");
    if (!integer(e, "flags", f.segment_flags[s])) return fail(error, where + ": bad \"flags\"");
  }
  f.q_parent_segment[0] = f.q_earth_segment[0];
  if (const auto joints = j.find("joints"); joints != j.end() && joints->is_array()) {
    for (const json& e : *joints) {
      if (!e.is_object() || !e.contains("name") || !e["name"].is_string()) continue;
      const auto seg = segment_from_name(e["name"].get<std::string>());
      if (!seg || *seg == Segment::pelvis) continue;
      std::array<float, 4> q{};
      if (e.contains("q") && unit_quaternion(e["q"], q)) f.q_parent_segment[index(*seg)] = q;
      f.joint_violation_deg[index(*seg)] = number_or(e, "violation_deg", 0);
    }
  }
  if (const auto sensors = j.find("sensors"); sensors != j.end() && sensors->is_array()) {
    for (const json& e : *sensors) {
      if (f.sensor_count >= static_cast<uint32_t>(kMaxSensors)) break;
      if (!e.is_object()) continue;
      SensorStatus& st = f.sensors[f.sensor_count++];
      if (const auto n = e.find("name"); n != e.end() && n->is_string()) {
        const std::string name = n->get<std::string>();
        std::strncpy(st.name, name.c_str(), sizeof st.name - 1);
      }
      if (const auto s = e.find("segment"); s != e.end() && s->is_string())
        if (const auto seg = segment_from_name(s->get<std::string>()))
          st.segment = static_cast<int8_t>(index(*seg));
      if (!integer(e, "state", st.state)) st.state = 4;
      integer(e, "flags", st.flags);
      integer(e, "drops", st.drops);
      integer(e, "errors", st.errors);
      st.rate_hz = number_or(e, "rate_hz", 0);
      st.last_age_ms = number_or(e, "age_ms", 0);
    }
  }
  out = f;
  return true;
}

}  // namespace mocap::viewer
