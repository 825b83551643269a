// A recorded session played back (--play FILE.mocap): the poses the daemon computed and recorded,
// looped at their recorded timing, with pause and seek. Only an index of the pose blocks is held
// in memory (16 bytes a frame); each shown frame is read from the file on demand.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "mocap/session/session_reader.hpp"
#include "mocap/viewer/pose_source.hpp"

namespace mocap::viewer {

class SessionSource final : public PlaybackSource {
 public:
  /// Opens and indexes the file; throws std::runtime_error naming the file and the problem (not
  /// a session, unsupported version, no pose frames). A torn or corrupt tail is not an error:
  /// the frames before it play, and status() says where the file ends.
  explicit SessionSource(const std::string& path);
  bool poll(double t_s, std::vector<PoseFrame>& frames) override;
  std::string status() const override;
  const BodyDimensions* dimensions() const override { return &dims_; }

  int frame_count() const { return static_cast<int>(index_.size()); }
  double duration_s() const { return duration_s_; }
  /// Index of the frame shown at playback position `position_s` (wraps around the recording).
  int frame_at(double position_s) const;

 private:
  struct Entry {
    int64_t t_ns;     ///< the pose's timestamp
    uint64_t offset;  ///< its block in the file (or the compressed block holding it)
    uint32_t inner;   ///< SessionReader::Block::inner (0: not in a compressed block)
  };
  std::string name_;
  SessionReader reader_;
  std::vector<Entry> index_;
  BodyDimensions dims_;
  std::string tail_note_;
  double duration_s_ = 0;
  int shown_ = -1;
};

/// Body height that the recorded joint positions were computed with: the daemon's body model
/// scales every segment with height, so the ratio of the recorded joint offsets to those of a
/// 1 m body gives it. Falls back to `fallback_m` for a degenerate frame.
double body_height_from_pose(const PoseFrame& frame, double fallback_m);

}  // namespace mocap::viewer
