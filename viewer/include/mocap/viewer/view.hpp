// One viewer frame: the avatars, floor, shadows, flagged-segment labels and heads-up display,
// drawn into the bound framebuffer. Shared by the window, the screenshot mode and the bench.
#pragma once

#include <string>
#include <vector>

#include "mocap/viewer/avatar_geometry.hpp"
#include "mocap/viewer/camera.hpp"
#include "mocap/viewer/scene_renderer.hpp"
#include "mocap/viewer/text_renderer.hpp"

namespace mocap::viewer {

struct ViewSettings {
  AvatarStyle style;
  bool earth_axes = true;
  bool hud = true;
  bool labels = true;   ///< label flagged segments
  bool follow = false;  ///< keep the camera target over avatar 0's pelvis
  bool shadows = true;
};

/// What the heads-up display shows besides the frames themselves.
struct HudInfo {
  double fps = 0;
  std::string source;
  bool paused = false;
  std::string calibration_pose;    ///< last requested ("N-POSE", "T-POSE")
  std::string message;             ///< last control reply or error
  std::string calibration_prompt;  ///< from the daemon's status (calibration_prompt())
};

class View {
 public:
  explicit View(BodyDimensions dims);  ///< needs a current GL context

  OrbitCamera camera;
  ViewSettings settings;
  HudInfo hud;
  std::vector<PoseFrame> frames;  ///< one per avatar

  void render(int width, int height);
  const BodyDimensions& dims() const { return dims_; }
  /// Capsules drawn in the last frame (for the bench's report).
  size_t capsule_count() const { return capsules_.size(); }

 private:
  BodyDimensions dims_;
  SceneRenderer scene_;
  TextRenderer text_;
  std::vector<CapsuleInstance> capsules_;
};

/// Adds the heads-up display and segment labels to `text` (see docs/viewer.md for the layout).
void build_hud(TextRenderer& text, const HudInfo& hud, const ViewSettings& settings,
               const std::vector<PoseFrame>& frames, const OrbitCamera& camera,
               const BodyDimensions& dims, int width, int height);

}  // namespace mocap::viewer
