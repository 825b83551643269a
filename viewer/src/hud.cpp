// Heads-up display: frame rate and frame number, source, modes, per-sensor status, recording
// indicator, calibration prompt and countdown, key help, and labels on flagged segments.
#include <cstdio>

#include "mocap/viewer/view.hpp"

namespace mocap::viewer {
namespace {

constexpr Rgba kWhite = {0.92f, 0.93f, 0.95f, 1};
constexpr Rgba kGrey = {0.62f, 0.64f, 0.68f, 1};
constexpr Rgba kGreen = {0.35f, 0.85f, 0.40f, 1};
constexpr Rgba kYellow = {0.95f, 0.80f, 0.20f, 1};
constexpr Rgba kRed = {0.95f, 0.22f, 0.18f, 1};
constexpr Rgba kPanel = {0.04f, 0.045f, 0.06f, 0.72f};

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
    default:
      return "ERROR";
  }
}

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

void sensor_table(TextRenderer& t, const PoseFrame& f, float x, float y) {
  const int scale = 2;
  const float lh = TextRenderer::line_height(scale);
  const int n = static_cast<int>(std::min<uint32_t>(f.sensor_count, kMaxSensors));
  const char* header = "SENSOR SEGMENT     STATE    HZ AGE MS DROP FLAGS";
  t.rect(x - 4, y - 4, TextRenderer::text_width(header, scale) + 8,
         lh * static_cast<float>(n + 1) + 6, kPanel);
  t.text(x, y, scale, header, kGrey);
  char line[128];
  for (int i = 0; i < n; ++i) {
    const SensorStatus& st = f.sensors[static_cast<size_t>(i)];
    char name[sizeof st.name + 1] = {};
    std::snprintf(name, sizeof name, "%.*s", static_cast<int>(sizeof st.name), st.name);
    const char* seg = st.segment >= 0 && st.segment < kSegmentCount
                          ? kSegmentNames[static_cast<size_t>(st.segment)].data()
                          : "-";
    std::snprintf(line, sizeof line, "%-6.6s %-11.11s %-7s %4.0f %6.0f %4u %s%s", name, seg,
                  state_name(st.state), static_cast<double>(st.rate_hz),
                  static_cast<double>(st.last_age_ms), st.drops,
                  (st.flags & kSegMagDisturbed)     ? "MAG "
                  : (st.flags & kSegMagNoReference) ? "MAG? "
                                                    : "",
                  (st.flags & kSegAtRest) ? "REST" : "");
    t.text(x, y + lh * static_cast<float>(i + 1), scale, line, state_colour(st));
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
        panel_text(t, px->x() + 14, px->y() - 8, 2, line, {rgb[0], rgb[1], rgb[2], 1});
      }
    }
  }
  if (!settings.hud) return;

  const float lh = TextRenderer::line_height(2);
  std::snprintf(line, sizeof line, "MOCAP-VIEWER  %5.0f FPS  FRAME %llu", hud.fps,
                static_cast<unsigned long long>(f ? f->frame : 0));
  panel_text(t, 12, 12, 2, line, kWhite);
  panel_text(t, 12, 12 + lh, 2, hud.source.c_str(), kGrey);
  std::snprintf(line, sizeof line, "%s%s%s%s", settings.style.stick ? "STICK" : "SOLID",
                settings.style.sensor_axes ? "  AXES" : "", settings.follow ? "  FOLLOW" : "",
                hud.paused ? "  PAUSED" : "");
  panel_text(t, 12, 12 + 2 * lh, 2, line, hud.paused ? kYellow : kGrey);

  if (f) {
    // Top right: recording indicator and source kind.
    float x = static_cast<float>(width) - 12;
    if (f->flags & kFrameRecording) {
      x -= TextRenderer::text_width("REC", 3) + 30;
      t.rect(x, 12, 20, 20, kRed);
      t.text(x + 28, 10, 3, "REC", kRed);
    }
    const char* kind = (f->flags & kFrameReplay) ? "REPLAY" : (f->flags & kFrameDemo) ? "DEMO" : "";
    if (*kind) panel_text(t, x - TextRenderer::text_width(kind, 2) - 20, 14, 2, kind, kGrey);

    if (f->sensor_count > 0) sensor_table(t, *f, 12, 12 + 4 * lh);

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
      const int scale =
          TextRenderer::text_width(prompt, 3) + 24 > static_cast<float>(width) ? 2 : 3;
      panel_text(t, 0.5f * (static_cast<float>(width) - TextRenderer::text_width(prompt, scale)),
                 0.22f * static_cast<float>(height), scale, prompt, kYellow);
    }
  }

  const float bottom = static_cast<float>(height) - 12 - lh;
  if (!hud.message.empty()) panel_text(t, 12, bottom - lh - 6, 2, hud.message.c_str(), kYellow);
  const char* keys =
      "DRAG ORBIT  RDRAG PAN  WHEEL ZOOM  R RESET  F FOLLOW  S STICK  A AXES  E EARTH  "
      "SPACE PAUSE  N/T CALIB  H HEADING  Q QUIT";
  const int key_scale = TextRenderer::text_width(keys, 2) + 24 > static_cast<float>(width) ? 1 : 2;
  panel_text(t, 12, static_cast<float>(height) - 12 - TextRenderer::line_height(key_scale),
             key_scale, keys, kGrey);
}

}  // namespace mocap::viewer
