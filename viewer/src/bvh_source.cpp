// BVH playback clock (pause, seek, loop) over BvhMotion frames.
#include "mocap/viewer/bvh_source.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace mocap::viewer {

BvhSource::BvhSource(const std::string& path) {
  const auto slash = path.rfind('/');
  name_ = slash == std::string::npos ? path : path.substr(slash + 1);
  try {
    motion_ = std::make_unique<BvhMotion>(load_bvh(path));
  } catch (const std::exception& e) {
    throw std::runtime_error("--play " + path + ": " + e.what());
  }
  if (motion_->frames() < 1 || !(motion_->frame_time_s() > 0))
    throw std::runtime_error("--play " + path + ": no frames");
}

int BvhSource::frame_at(double position_s) const {
  const int n = motion_->frames();
  const auto k = static_cast<long long>(std::floor(position_s / motion_->frame_time_s()));
  return static_cast<int>(((k % n) + n) % n);
}

bool BvhSource::poll(double t_s, std::vector<PoseFrame>& frames) {
  const int k = frame_at(advance(t_s));
  if (k == shown_ && !frames.empty()) return false;
  frames.resize(1);
  motion_->to_pose_frame(k, frames[0]);
  frames[0].flags |= kFrameReplay;
  shown_ = k;
  return true;
}

std::string BvhSource::status() const {
  char s[160];
  const double total = motion_->frames() * motion_->frame_time_s();
  std::snprintf(s, sizeof s, "PLAYING %s  FRAME %d/%d  %.1f/%.1f S", name_.c_str(), shown_ + 1,
                motion_->frames(), (shown_ + 1) * motion_->frame_time_s(), total);
  return s;
}

}  // namespace mocap::viewer
