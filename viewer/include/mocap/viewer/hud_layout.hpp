// Layout of the HUD's text, measured against the window width with the bitmap font's cell size
// (no GL): the sensor table shows every sensor's whole name, drops columns and then shrinks the
// font when the window is narrow, and puts a name on its own line when even name and state do
// not fit, and lists only the sensors that fit a short window; long lines (key help, messages)
// wrap at word gaps.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "mocap/skeleton/pose_frame.hpp"

namespace mocap::viewer {

/// Width in pixels of `s` in the bitmap font at `scale` pixels per font pixel.
float hud_text_width(std::string_view s, int scale);

struct HudLine {
  std::string text;
  int sensor = -1;  ///< the sensor this line shows (colour); -1 for the header
};

struct SensorTableLayout {
  int scale = 2;
  std::vector<HudLine> lines;  ///< header first
  float width_px = 0;          ///< widest line
};

/// The sensor table of `f` laid out to fit `max_width_px` (if anything can: a name longer than
/// the window at the smallest scale is wrapped over several lines) and `max_height_px` (the
/// smaller font first; then the sensors that do not fit are counted on a last "+N MORE" line).
SensorTableLayout layout_sensor_table(const PoseFrame& f, float max_width_px,
                                      float max_height_px = 1e9f);

/// `s` broken into lines no wider than `max_width_px` at `scale`, at spaces (a word wider than
/// the line is cut).
std::vector<std::string> wrap_hud_text(std::string_view s, int scale, float max_width_px);

}  // namespace mocap::viewer
