// The local daemon's shared posture as a pose source. Read-only mapping and a seqlock read: the
// viewer can never make the daemon wait. Waits (without blocking) for the daemon to start.
#pragma once

#include <memory>

#include "mocap/outputs/posture_shm.hpp"
#include "mocap/viewer/pose_source.hpp"

namespace mocap::viewer {

class ShmSource final : public PoseSource {
 public:
  explicit ShmSource(std::string name);
  bool poll(double t_s, std::vector<PoseFrame>& frames) override;
  std::string status() const override;
  void set_paused(bool paused) override { paused_ = paused; }

 private:
  std::string name_;
  std::unique_ptr<outputs::PostureReader> reader_;
  std::string error_;
  double next_try_s_ = 0, last_change_s_ = 0;
  uint64_t last_sequence_ = 0;
  bool paused_ = false;
};

}  // namespace mocap::viewer
