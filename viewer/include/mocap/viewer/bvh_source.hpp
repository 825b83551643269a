// A BVH file played back (--play FILE.bvh) through the skeleton's BvhMotion: any BVH whose bones
// map onto our segments, looped, with pause and seek. The avatar takes the file's proportions.
#pragma once

#include <memory>

#include "mocap/skeleton/bvh.hpp"
#include "mocap/viewer/pose_source.hpp"

namespace mocap::viewer {

class BvhSource final : public PlaybackSource {
 public:
  /// Loads and maps the file; throws std::runtime_error naming the file and the problem.
  explicit BvhSource(const std::string& path);
  bool poll(double t_s, std::vector<PoseFrame>& frames) override;
  std::string status() const override;
  const BodyDimensions* dimensions() const override { return &motion_->dimensions(); }

  /// Frame index shown at playback position `position_s` (wraps around the clip).
  int frame_at(double position_s) const;

 private:
  std::string name_;
  std::unique_ptr<BvhMotion> motion_;
  int shown_ = -1;
};

}  // namespace mocap::viewer
