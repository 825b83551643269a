// Bridges sensor dropouts in a recorded pose stream (offline: export, replay to files). While a
// sensor is silent the live pipeline holds its segment's last orientation (it cannot know the
// future); with the poses after the gap in hand, the bridge slerps the segment across it — each
// segment's keys are the frames where its sensor delivered a new sample (SensorStatus::
// last_age_ms gives the sample's time) — and recomputes the frame's joint rotations and joint
// positions. Gaps longer than max_bridge_ns stay held, as recorded. Poses come out in order,
// delayed by max_bridge_ns.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "mocap/skeleton/body_model.hpp"
#include "mocap/skeleton/interpolation.hpp"
#include "mocap/skeleton/pose_frame.hpp"

namespace mocap {

class DropoutBridge {
 public:
  /// nominal_gap_ns: two consecutive samples of a sensor further apart than this are a gap.
  explicit DropoutBridge(const BodyDimensions& dims, int64_t nominal_gap_ns = 50'000'000,
                         int64_t max_bridge_ns = 500'000'000);
  /// Adds the next pose (t_ns increasing; older ones are ignored).
  void push(const PoseFrame& f);
  /// No more poses: every queued pose becomes available.
  void finish() { finished_ = true; }
  /// The oldest pose whose bridging is settled (max_bridge_ns behind the newest, or after
  /// finish()); false when none is.
  bool next(PoseFrame& out);
  /// Segment-frames whose orientation was bridged so far.
  long bridged() const { return bridged_; }

 private:
  BodyDimensions dims_;
  int64_t max_bridge_ns_;
  std::array<OrientationTrack, kSegmentCount> tracks_;
  /// The queued poses, oldest first: a ring over ring_, doubled when full and never shrunk (no
  /// allocation per pose once it holds max_bridge_ns of them; a deque allocated every pose).
  std::vector<PoseFrame> ring_;
  std::size_t head_ = 0, count_ = 0;
  PoseFrame& queued(std::size_t i) { return ring_[(head_ + i) % ring_.size()]; }
  bool finished_ = false;
  long bridged_ = 0;
};

}  // namespace mocap
