// Heads-up display: frame rate and frame number, source, modes, per-sensor status, recording
// indicator, calibration prompt and countdown, key help, and labels on flagged segments.
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "mocap/viewer/hud_layout.hpp"
#include "mocap/viewer/view.hpp"

namespace mocap::viewer {
namespace {

constexpr Rgba kWhite = {0.92f, 0.93f, 0.95f, 1};
constexpr Rgba kGrey = {0.62f, 0.64f, 0.68f, 1};
constexpr Rgba kGreen = {0.35f, 0.85f, 0.40f, 1};
constexpr Rgba kYellow = {0.95f, 0.80f, 0.20f, 1};
constexpr Rgba kRed = {0.95f, 0.22f, 0.18f, 1};
constexpr Rgba kPanel = {0.04f, 0.045f, 0.06f, 0.72f};

Rgba state_colour(const SensorStatus& st) {
  if (st.state == 2) return (st.flags & kSegMagDisturbed) ? kYellow : kGreen;
  if (st.state == 1) return kYellow;
  if (st.state == 0) return kGrey;
  return kRed;
}

void panel_text(TextRenderer& t, float x, float y, int scale, const char* s, const Rgba& c) {
  const float pad = 2.0f * static_cast<float>(scale);
  t.rect(x - pad, y - pad, TextRenderer::text_width(s, scale) + 2 * pad,
         TextRenderer::line_height(scale) + pad, kPanel);
  t.text(x, y, scale, s, c);
}

/// `s` at `scale` (one step smaller when it does not fit), wrapped to `max_w` on panels from
/// (x, y) downwards; returns the height used.
float panel_lines(TextRenderer& t, float x, float y, int scale, const std::string& s, const Rgba& c,
                  float max_w) {
  if (scale > 1 && hud_text_width(s, scale) > max_w) --scale;
  const float lh = TextRenderer::line_height(scale);
  float used = 0;
  for (const std::string& line : wrap_hud_text(s, scale, max_w)) {
    panel_text(t, x, y + used, scale, line.c_str(), c);
    used += lh;
  }
  return used;
}

/// The sensor table (hud_layout.hpp: whole names, as many columns as fit `max_w`).
void sensor_table(TextRenderer& t, const PoseFrame& f, float x, float y, float max_w, float max_h) {
  const SensorTableLayout l = layout_sensor_table(f, max_w, max_h);
  const float lh = TextRenderer::line_height(l.scale);
  t.rect(x - 4, y - 4, l.width_px + 8, lh * static_cast<float>(l.lines.size()) + 6, kPanel);
  for (size_t i = 0; i < l.lines.size(); ++i) {
    const HudLine& h = l.lines[i];
    t.text(x, y + lh * static_cast<float>(i), l.scale, h.text,
           h.sensor < 0 ? kGrey : state_colour(f.sensors[static_cast<size_t>(h.sensor)]));
  }
}

}  // namespace

void build_hud(TextRenderer& t, const HudInfo& hud, const ViewSettings& settings,
               const std::vector<PoseFrame>& frames, const OrbitCamera& camera,
               const BodyDimensions& dims, int width, int height) {
  const PoseFrame* f = frames.empty() ? nullptr : &frames[0];
  char line[192];
  if (settings.labels && f) {
    // Flagged segments of the first avatars (a crowd would bury the view in labels).
    const size_t labelled = std::min<size_t>(frames.size(), 4);
    std::array<char, 32> label{};
    for (size_t a = 0; a < labelled; ++a) {
      if (!pose_is_finite(frames[a])) continue;
      for (int s = 0; s < kSegmentCount; ++s) {
        segment_label(frames[a], s, label);
        if (!label[0]) continue;
        const auto px = camera.project(segment_midpoint(frames[a], dims, s), width, height);
        if (!px) continue;
        std::snprintf(line, sizeof line, "%s %s", kSegmentNames[static_cast<size_t>(s)].data(),
                      label.data());
        const auto rgb = segment_rgb(s, frames[a].segment_flags[static_cast<size_t>(s)]);
        // Beside the segment, moved left where it would leave the window.
        const float x = std::min(
            px->x() + 14, static_cast<float>(width) - 16 - TextRenderer::text_width(line, 2));
        panel_text(t, std::max(4.0f, x), px->y() - 8, 2, line, {rgb[0], rgb[1], rgb[2], 1});
      }
    }
  }
  if (!settings.hud) return;

  // Everything stays within the window: 12 px margins, panels' padding.
  const float max_w = std::max(16.0f, static_cast<float>(width) - 32);

  // Bottom first (the table above must end before it): the key help (smaller, then wrapped, in
  // a narrow window) and the last message above it.
  const std::string keys =
      "DRAG ORBIT  RDRAG PAN  WHEEL ZOOM  R RESET  F FOLLOW  S STICK  A AXES  E EARTH  "
      "SPACE PAUSE  N/T CALIB  H HEADING  Q QUIT";
  const int key_scale = hud_text_width(keys, 2) > max_w ? 1 : 2;
  const std::vector<std::string> key_lines = wrap_hud_text(keys, key_scale, max_w);
  const float key_lh = TextRenderer::line_height(key_scale);
  float bottom = static_cast<float>(height) - 12 - key_lh * static_cast<float>(key_lines.size());
  for (size_t i = 0; i < key_lines.size(); ++i)
    panel_text(t, 12, bottom + key_lh * static_cast<float>(i), key_scale, key_lines[i].c_str(),
               kGrey);
  if (!hud.message.empty()) {
    const int scale = hud_text_width(hud.message, 2) > max_w ? 1 : 2;
    const auto msg = wrap_hud_text(hud.message, scale, max_w);
    bottom -= TextRenderer::line_height(scale) * static_cast<float>(msg.size()) + 6;
    panel_lines(t, 12, bottom, scale, hud.message, kYellow, max_w);
  }

  // Top right: recording indicator and source kind, unless the window is too narrow for them
  // beside the top-left lines (then the kind joins the mode line).
  const char* kind = !f                          ? ""
                     : (f->flags & kFrameReplay) ? "REPLAY"
                     : (f->flags & kFrameDemo)   ? "DEMO"
                                                 : "";
  std::snprintf(line, sizeof line, "MOCAP-VIEWER  %5.0f FPS  FRAME %llu", hud.fps,
                static_cast<unsigned long long>(f ? f->frame : 0));
  const std::string title = line;
  const float left_w = std::max(hud_text_width(title, 2), hud_text_width(hud.source, 2));
  float right_x = static_cast<float>(width) - 12;
  if (f && (f->flags & kFrameRecording)) right_x -= TextRenderer::text_width("REC", 3) + 30;
  const float kind_x = right_x - TextRenderer::text_width(kind, 2) - 20;
  const bool kind_top_right = *kind && kind_x > 12 + left_w + 12;
  if (f && (f->flags & kFrameRecording) && right_x > 12 + left_w + 12) {
    t.rect(right_x, 12, 20, 20, kRed);
    t.text(right_x + 28, 10, 3, "REC", kRed);
  }
  if (kind_top_right) panel_text(t, kind_x, 14, 2, kind, kGrey);

  float y = 12;
  y += panel_lines(t, 12, y, 2, title, kWhite, max_w);
  y += panel_lines(t, 12, y, 2, hud.source, kGrey, max_w);
  std::snprintf(line, sizeof line, "%s%s%s%s%s%s", settings.style.stick ? "STICK" : "SOLID",
                settings.style.sensor_axes ? "  AXES" : "", settings.follow ? "  FOLLOW" : "",
                hud.paused ? "  PAUSED" : "", kind_top_right || !*kind ? "" : "  ",
                kind_top_right ? "" : kind);
  y += panel_lines(t, 12, y, 2, line, hud.paused ? kYellow : kGrey, max_w);
  if (!f) return;
  const float lh = TextRenderer::line_height(2);
  if (f->sensor_count > 0) sensor_table(t, *f, 12, y + lh, max_w, bottom - (y + lh) - 12);

  // Calibration prompt and countdown, centred.
  const char* prompt = nullptr;
  if (f->flags & kFrameCalibrating) {
    std::snprintf(line, sizeof line, "CALIBRATING%s%s: HOLD STILL  %.1f S",
                  hud.calibration_pose.empty() ? "" : " ", hud.calibration_pose.c_str(),
                  static_cast<double>(f->calib_countdown_s));
    prompt = line;
  } else if (!hud.calibration_prompt.empty() && !(f->flags & kFrameReplay)) {
    prompt = hud.calibration_prompt.c_str();  // the moves still to do, or a refusal
  } else if (!(f->flags & (kFrameCalibrated | kFrameReplay | kFrameDemo))) {
    prompt = "NOT CALIBRATED: PRESS N (N-POSE) OR T (T-POSE)";
  }
  if (prompt) {
    const int scale = hud_text_width(prompt, 3) + 24 > static_cast<float>(width) ? 2 : 3;
    const float w = std::min(hud_text_width(prompt, scale), max_w);
    panel_lines(t, 0.5f * (static_cast<float>(width) - w), 0.22f * static_cast<float>(height),
                scale, prompt, kYellow, max_w);
  }
}

}  // namespace mocap::viewer
