// A viewer frame: capsules for every avatar, the scene, then the HUD on top.
#include "mocap/viewer/view.hpp"

namespace mocap::viewer {

View::View(BodyDimensions dims) : dims_(std::move(dims)) {
  capsules_.reserve(200 * 64);
}

void View::render(int width, int height) {
  capsules_.clear();
  for (const PoseFrame& f : frames)
    append_avatar(f, dims_, settings.style, capsules_);
  if (settings.earth_axes) append_earth_axes(0.5f, capsules_);
  if (settings.follow && !frames.empty() && pose_is_finite(frames[0])) {
    const auto& p = frames[0].p_earth_segment_m[0];
    camera.target_m.x() = p[0];
    camera.target_m.y() = p[1];
  }
  SceneRenderer::Options opt;
  // Crowds: coarser capsules and no shadow pass (llvmpipe shades vertices on one thread, so
  // triangles are what a crowd costs).
  const bool crowd = frames.size() > 24;
  opt.shadows = settings.shadows && !crowd;
  opt.low_detail = crowd;
  scene_.draw(camera, width, height, capsules_, opt);
  if (!settings.hud && !settings.labels) return;
  text_.begin(width, height);
  build_hud(text_, hud, settings, frames, camera, dims_, width, height);
  text_.flush();
}

}  // namespace mocap::viewer
