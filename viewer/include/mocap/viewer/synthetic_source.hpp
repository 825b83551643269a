// A procedural performer for development, tests and documentation: every avatar walks in place
// with swinging arms; avatar 0 cycles through the flagged states the viewer must show
// (joint limit violated, stale sensor, disturbed magnetometer) on a fixed 6 s schedule.
#pragma once

#include "mocap/viewer/pose_source.hpp"

namespace mocap::viewer {

class SyntheticSource final : public PoseSource {
 public:
  SyntheticSource(int avatars, BodyDimensions dims);
  bool poll(double t_s, std::vector<PoseFrame>& frames) override;
  std::string status() const override;
  bool seekable() const override { return true; }
  void set_paused(bool paused) override { paused_ = paused; }
  void seek_by(double dt_s) override { offset_s_ += dt_s; }

  /// The pose of avatar `i` at time `t_s` (used by poll and by tests).
  void pose_at(int i, double t_s, PoseFrame& out) const;

 private:
  int avatars_;
  BodyDimensions dims_;
  bool paused_ = false;
  double offset_s_ = 0, last_t_s_ = 0;
  uint64_t frame_ = 0;
};

}  // namespace mocap::viewer
