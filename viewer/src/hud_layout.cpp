// HUD text layout against the window width (mocap/viewer/hud_layout.hpp).
#include "mocap/viewer/hud_layout.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>

#include "mocap/viewer/bitmap_font.hpp"

namespace mocap::viewer {
namespace {

const char* state_name(uint8_t s) {
  switch (s) {
    case 0:
      return "ABSENT";
    case 1:
      return "CONNECT";
    case 2:
      return "OK";
    case 3:
      return "STALE";
    case 5:
      return "LOST";
    default:
      return "ERROR";
  }
}

std::string sensor_name(const SensorStatus& st) {
  return std::string(st.name, strnlen(st.name, sizeof st.name));
}

/// Columns after the name, widest first: what a narrow window drops, last to first.
enum Columns { kState = 1, kSegment = 2, kRate = 4, kFlags = 8, kAgeDrops = 16 };

std::string row(const SensorStatus& st, int name_w, int cols) {
  char buf[160];
  int n = std::snprintf(buf, sizeof buf, "%-*s", name_w, sensor_name(st).c_str());
  const auto add = [&](const char* fmt, auto... v) {
    if (n < static_cast<int>(sizeof buf))
      n += std::snprintf(buf + n, sizeof buf - static_cast<size_t>(n), fmt, v...);
  };
  if (cols & kSegment)
    add(" %-11.11s", st.segment >= 0 && st.segment < kSegmentCount
                         ? kSegmentNames[static_cast<size_t>(st.segment)].data()
                         : "-");
  if (cols & kState) add(" %-7s", state_name(st.state));
  if (cols & kRate) add(" %4.0f", static_cast<double>(st.rate_hz));
  if (cols & kAgeDrops)
    add(" %6.0f %4u", static_cast<double>(st.last_age_ms), static_cast<unsigned>(st.drops));
  if (cols & kFlags)
    add(" %s%s",
        (st.flags & kSegMagDisturbed)     ? "MAG "
        : (st.flags & kSegMagNoReference) ? "MAG? "
                                          : "",
        (st.flags & kSegAtRest) ? "REST" : "");
  std::string s(buf, static_cast<size_t>(std::min<int>(n, sizeof buf - 1)));
  while (!s.empty() && s.back() == ' ')
    s.pop_back();
  return s;
}

std::string header(int name_w, int cols) {
  char buf[160];
  int n = std::snprintf(buf, sizeof buf, "%-*s", name_w, "SENSOR");
  const auto add = [&](const char* s) {
    if (n < static_cast<int>(sizeof buf))
      n += std::snprintf(buf + n, sizeof buf - static_cast<size_t>(n), "%s", s);
  };
  if (cols & kSegment) add(" SEGMENT    ");
  if (cols & kState) add(" STATE  ");
  if (cols & kRate) add("   HZ");
  if (cols & kAgeDrops) add(" AGE MS DROP");
  if (cols & kFlags) add(" FLAGS");
  std::string s(buf, static_cast<size_t>(std::min<int>(n, sizeof buf - 1)));
  while (!s.empty() && s.back() == ' ')
    s.pop_back();
  return s;
}

/// Widest line of the one-line-per-sensor table with these columns (the flags column counted at
/// its widest, so the table does not change shape when a flag appears).
float table_width(int name_w, int cols, int scale) {
  const int chars = name_w + ((cols & kSegment) ? 12 : 0) + ((cols & kState) ? 8 : 0) +
                    ((cols & kRate) ? 5 : 0) + ((cols & kAgeDrops) ? 12 : 0) +
                    ((cols & kFlags) ? 10 : 0);
  return static_cast<float>(chars * kCellW * scale);
}

}  // namespace

float hud_text_width(std::string_view s, int scale) {
  return static_cast<float>(s.size() * static_cast<size_t>(kCellW) * static_cast<size_t>(scale));
}

std::vector<std::string> wrap_hud_text(std::string_view s, int scale, float max_width_px) {
  const size_t per_line =
      std::max<size_t>(1, static_cast<size_t>(max_width_px / static_cast<float>(kCellW * scale)));
  std::vector<std::string> out;
  while (!s.empty()) {
    if (s.size() <= per_line) {
      out.emplace_back(s);
      break;
    }
    size_t cut = s.rfind(' ', per_line);
    if (cut == std::string_view::npos || cut == 0) cut = per_line;  // one long word: cut it
    out.emplace_back(s.substr(0, cut));
    s.remove_prefix(cut);
    while (!s.empty() && s.front() == ' ')
      s.remove_prefix(1);
  }
  return out;
}

namespace {

/// Cuts `l` to the lines that fit `max_height_px`, the last one replaced by "+N MORE" (N the
/// sensors not shown), and measures it.
void fit_height(SensorTableLayout& l, int sensors, float max_height_px) {
  const auto fits =
      static_cast<size_t>(std::max(2.0f, max_height_px / static_cast<float>(kCellH * l.scale)));
  if (l.lines.size() > fits) {
    l.lines.resize(fits - 1);
    const int shown = l.lines.back().sensor + 1;
    l.lines.push_back({"+" + std::to_string(sensors - shown) + " MORE", -1});
  }
  l.width_px = 0;
  for (const HudLine& h : l.lines)
    l.width_px = std::max(l.width_px, hud_text_width(h.text, l.scale));
}

}  // namespace

SensorTableLayout layout_sensor_table(const PoseFrame& f, float max_width_px, float max_height_px) {
  SensorTableLayout l;
  const int n = static_cast<int>(std::min<uint32_t>(f.sensor_count, kMaxSensors));
  int name_w = 6;  // "SENSOR"
  for (int i = 0; i < n; ++i)
    name_w = std::max<int>(name_w, static_cast<int>(sensor_name(f.sensors[i]).size()));
  // Column sets from the full table down to name + state, at scale 2 then 1.
  static constexpr int kSets[] = {kState | kSegment | kRate | kAgeDrops | kFlags,
                                  kState | kSegment | kRate | kFlags, kState | kSegment | kRate,
                                  kState | kSegment, kState};
  const bool tall_enough_at_2 = static_cast<float>((n + 1) * kCellH * 2) <= max_height_px;
  for (int scale : {2, 1}) {
    if (scale == 2 && !tall_enough_at_2) continue;
    for (int cols : kSets) {
      if (table_width(name_w, cols, scale) > max_width_px) continue;
      l.scale = scale;
      l.lines.push_back({header(name_w, cols), -1});
      for (int i = 0; i < n; ++i)
        l.lines.push_back({row(f.sensors[i], name_w, cols), i});
      fit_height(l, n, max_height_px);
      return l;
    }
  }
  // Too narrow even for name and state on one line: each name on its own line(s), whole, then
  // its state indented below.
  l.scale = 1;
  l.lines.push_back({"SENSOR / STATE", -1});
  for (int i = 0; i < n; ++i) {
    for (std::string& part : wrap_hud_text(sensor_name(f.sensors[i]), 1, max_width_px))
      l.lines.push_back({std::move(part), i});
    l.lines.push_back({std::string("  ") + state_name(f.sensors[i].state), i});
  }
  fit_height(l, n, max_height_px);
  return l;
}

}  // namespace mocap::viewer
