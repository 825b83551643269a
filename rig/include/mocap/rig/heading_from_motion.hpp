// 6D rigs: the heading alignment of a sensor whose site normal is vertical (top of the head,
// instep) cannot be read in the N-pose, so the calibration borrows the segment above's. This
// finds its own from motion: the horizontal part of a segment's earth-frame angular rate follows
// its reference segment's (the nearest one above with an aligned sensor: a foot pitches with its
// shank, a head nods and turns with the torso), so the yaw that maps the one onto the other,
// fitted over the motion (a rate-product weighted circular mean, forgotten over tau_s so slow
// gyro drift is followed), is the missing alignment. Whatever the joint adds on its own is noise
// to the fit, not a bias, as long as it is not correlated with the reference's rate at another
// angle.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>

#include "mocap/core/segments.hpp"

namespace mocap::rig {

struct HeadingFromMotionOptions {
  double tau_s = 30.0;  ///< forgetting time of the fit, seconds of sample time
  /// Evidence before a yaw is given: the integral of |w_child,h| |w_ref,h| dt, rad^2/s (about a
  /// second of walking).
  double min_evidence = 0.1;
  /// A reference sample older than this is not paired with a child's sample, seconds.
  double max_pair_age_s = 0.02;
};

class HeadingFromMotion {
 public:
  explicit HeadingFromMotion(HeadingFromMotionOptions options = {}) : opt_(options) {}

  /// Starts over after a calibration: `reference[s]` is the segment whose rate segment s's is
  /// fitted to, -1 for segments whose heading needs nothing.
  void reset(const std::array<int, kSegmentCount>& reference);
  /// The newest earth-frame angular rate of a segment's sensor under the alignment in use.
  void add(int segment, const Eigen::Vector3d& w_earth_rad_s, int64_t t_ns);
  /// The yaw (rad, about the vertical) that would align the segment's sensor, once there is
  /// enough evidence; false before.
  bool estimate(int segment, double& yaw_rad) const;
  /// The caller turned the segment's alignment by yaw_rad: the fit continues in the new frame.
  void applied(int segment, double yaw_rad);
  bool active() const { return active_; }

 private:
  HeadingFromMotionOptions opt_;
  bool active_ = false;
  std::array<int, kSegmentCount> ref_{};
  std::array<Eigen::Vector2d, kSegmentCount> last_w_{};
  std::array<int64_t, kSegmentCount> last_t_ns_{};
  std::array<bool, kSegmentCount> have_{};
  /// Per fitted segment: sum of |a||b| (cos, sin) of the angle from its rate to the reference's.
  std::array<Eigen::Vector2d, kSegmentCount> sum_{};
  std::array<double, kSegmentCount> evidence_{};
};

}  // namespace mocap::rig
