// The HUD's text layout against the window width (issue 22 item 11): a long sensor name is shown
// whole and every line fits the window, from a wide window (all columns, one line per sensor)
// down to a tiny one (name on its own line); long text wraps at word gaps.
#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "mocap/viewer/hud_layout.hpp"

using namespace mocap;
using namespace mocap::viewer;

namespace {

PoseFrame frame_with(const std::vector<std::string>& names) {
  PoseFrame f;
  f.sensor_count = static_cast<uint32_t>(names.size());
  for (size_t i = 0; i < names.size(); ++i) {
    std::strncpy(f.sensors[i].name, names[i].c_str(), sizeof f.sensors[i].name - 1);
    f.sensors[i].segment = static_cast<int8_t>(i);
    f.sensors[i].state = 2;
    f.sensors[i].rate_hz = 100;
  }
  return f;
}

/// All the text shown for sensor i, its lines joined.
std::string text_of(const SensorTableLayout& l, int i) {
  std::string s;
  for (const HudLine& h : l.lines)
    if (h.sensor == i) s += h.text;
  return s;
}

}  // namespace

TEST(HudLayout, LongSensorNameWholeAndFitsEveryWidth) {
  const std::string longest = "capteur_avant_bras_gau";  // 22 characters, the frame holds 23
  const PoseFrame f = frame_with({"pelvis", longest, "foot_r"});
  for (float width : {1280.0f, 640.0f, 400.0f, 320.0f, 200.0f, 120.0f}) {
    const float max_w = width - 32;
    const SensorTableLayout l = layout_sensor_table(f, max_w);
    ASSERT_FALSE(l.lines.empty());
    EXPECT_LE(l.width_px, max_w) << width;
    for (const HudLine& h : l.lines)
      EXPECT_LE(hud_text_width(h.text, l.scale), max_w) << width << ": " << h.text;
    EXPECT_NE(text_of(l, 1).find(longest), std::string::npos) << width;
    // A wrapped name is cut into whole pieces: joined, it is the name again.
    for (int i = 0; i < 3; ++i)
      EXPECT_FALSE(text_of(l, i).empty()) << width;
  }
  // Wide: one line per sensor with every column, at the normal scale.
  const SensorTableLayout wide = layout_sensor_table(f, 1280 - 32);
  EXPECT_EQ(wide.scale, 2);
  EXPECT_EQ(wide.lines.size(), 4u);
  EXPECT_NE(wide.lines[0].text.find("DROP"), std::string::npos) << wide.lines[0].text;
  // Narrow: fewer columns or a smaller font, never a cut name.
  const SensorTableLayout narrow = layout_sensor_table(f, 320 - 32);
  EXPECT_TRUE(narrow.scale == 1 || narrow.lines[0].text.find("DROP") == std::string::npos);
}

TEST(HudLayout, WrapsAtWordGaps) {
  const std::string keys = "DRAG ORBIT  RDRAG PAN  WHEEL ZOOM  R RESET  F FOLLOW  Q QUIT";
  const auto lines = wrap_hud_text(keys, 1, 20 * 6);  // 20 characters a line
  ASSERT_GT(lines.size(), 2u);
  std::string joined;
  for (const auto& l : lines) {
    EXPECT_LE(l.size(), 20u) << l;
    EXPECT_NE(l.front(), ' ');
    joined += l;
  }
  std::string no_spaces = keys;
  std::erase(no_spaces, ' ');
  std::erase(joined, ' ');
  EXPECT_EQ(joined, no_spaces);
  EXPECT_EQ(wrap_hud_text("short", 2, 1000).size(), 1u);
}
