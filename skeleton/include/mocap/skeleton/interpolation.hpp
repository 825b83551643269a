// Key-frame interpolation: whole-pose interpolation between two PoseFrames (shortest-path slerp of
// every rotation, linear positions), a fixed-capacity orientation track per sensor that bridges
// short dropouts by slerping across the gap, and a resampler that turns irregular poses into a
// fixed frame rate. No allocation after construction.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>

#include "mocap/skeleton/pose_frame.hpp"

namespace mocap {

/// out = a at t = 0, b at t = 1 (rotations by slerp_shortest, positions and violations linear;
/// flags, frame number and sensors from the nearer frame; t_ns interpolated).
void interpolate_pose(const PoseFrame& a, const PoseFrame& b, double t, PoseFrame& out);

/// One orientation over time: the newest kCapacity keys (t_ns increasing).
class OrientationTrack {
 public:
  static constexpr int kCapacity = 256;
  struct Sample {
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    bool valid = false;    ///< false: no key yet
    bool bridged = false;  ///< t fell in a gap longer than nominal_gap_ns (slerped across)
    bool held = false;     ///< t outside the keys: nearest key held
  };
  /// nominal_gap_ns: keys further apart than this count as a dropout; max_bridge_ns: longer gaps
  /// are not interpolated (the earlier key is held).
  explicit OrientationTrack(int64_t nominal_gap_ns = 50'000'000,
                            int64_t max_bridge_ns = 500'000'000)
      : nominal_gap_ns_(nominal_gap_ns), max_bridge_ns_(max_bridge_ns) {}

  /// Adds a key; keys not newer than the newest, or non-finite, are ignored (returns false).
  bool push(int64_t t_ns, const Eigen::Quaterniond& q);
  Sample sample(int64_t t_ns) const;
  /// What sample() gives when it is bridged: true and q the slerp across the gap; false (q
  /// untouched) otherwise, at once for times after the newest gap (the dropout bridge asks
  /// every frame).
  bool bridged(int64_t t_ns, Eigen::Quaterniond& q) const;
  int size() const { return count_; }
  void clear() {
    count_ = 0;
    t_after_gap_ns_ = INT64_MIN;
  }

 private:
  /// The last key at or before t, for t strictly between the first and the last key.
  int key_before(int64_t t_ns) const;
  const Eigen::Quaterniond& q_at(int i) const { return q_[(head_ + i) % kCapacity]; }
  int64_t t_at(int i) const { return t_[(head_ + i) % kCapacity]; }
  std::array<int64_t, kCapacity> t_{};
  std::array<Eigen::Quaterniond, kCapacity> q_;
  int head_ = 0, count_ = 0;
  int64_t nominal_gap_ns_, max_bridge_ns_;
  /// The newest key that follows a gap longer than nominal_gap_ns: no time after it is bridged.
  int64_t t_after_gap_ns_ = INT64_MIN;
};

/// Resamples irregularly timed poses to a fixed rate. push() the poses as they come; next()
/// yields every output frame whose time is covered by the pushed poses (interpolated between
/// the two around it).
class PoseResampler {
 public:
  explicit PoseResampler(double rate_hz);
  void push(const PoseFrame& f);
  /// Writes the next fixed-rate frame if its time is covered; frame numbers count output frames.
  bool next(PoseFrame& out);
  int64_t period_ns() const { return period_ns_; }

 private:
  int64_t period_ns_;
  PoseFrame prev_{}, cur_{};
  int have_ = 0;
  int64_t t_next_ns_ = 0;
  uint64_t out_frame_ = 0;
};

}  // namespace mocap
