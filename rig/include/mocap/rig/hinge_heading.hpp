// 6D rigs: a knee's two segments' relative heading held to its hinge. Each 6D filter has a
// heading frame of its own that drifts (the vertical gyro's bias, integration under impacts):
// on the real running recording (shared/datasets/qmt-fullbody) the thigh's and shank's frames
// part by 35 deg in 100 s, and with the right axes the knee then sits far off its hinge. A hinge
// makes the relative heading observable (Laidig et al. 2017): its axis is one line seen from
// both segments, so with each segment's left axis (y) on the hinge axis (their mountings from
// hinge_axis.hpp), the two y axes in the earth frame must point the same way. Their horizontal
// angle is the relative heading's error; it is weighted by how horizontal both axes are (a
// vertical axis says nothing about heading) and integrated with time constant tau_s, so a
// drift of a degree a second is followed within tau_s and a moment of off-axis play (the
// tibia's rotation, soft tissue at a foot strike) moves it little. An error beyond
// max_error_deg is no drift (a wrong axis, a flip): it is not followed, and counted.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>

#include "mocap/rig/pending_yaw.hpp"

namespace mocap::rig {

struct HingeHeadingOptions {
  /// Time constant of the correction, seconds. The real run's knees (scripts/qmt-knees) sit
  /// closer to their hinge the faster it is (2 s: 8.9 / 10.0 deg, 10 s: 9.9 / 11.6). A segment
  /// whose own heading is lost (CMU 01_12's left leg, its gyros clipped) pulls its neighbour
  /// half way, the faster the sooner (random straps' worst segment excess 5.3 deg at 2 s, 3.3 at
  /// 10 s) unless its hip's range brings it back first (range_heading.hpp: 2.97 at 2 s).
  double tau_s = 2.0;
  /// The first start_s of a hold (followed_s: from when its axes are first found, or it starts
  /// over) at start_tau_s: the error then is the calibration's (the site prior's facings, a
  /// strap not where assumed), not drift, and the knee sits off its hinge until it is taken
  /// out. Real run alone 9.2 / 9.5 -> 9.1 / 9.3 deg (scripts/qmt-knees); CMU 6D unchanged.
  double start_s = 2.0;
  double start_tau_s = 0.5;
  double max_error_deg = 45.0;  ///< a larger error is refused, not followed
};

class HingeHeading {
 public:
  explicit HingeHeading(HingeHeadingOptions o = {}) : opt_(o) {}

  /// One sample: the hinge's axis seen from the upper and from the lower segment, each in the
  /// earth frame as that segment is aligned now; dt_s since the last sample. refuse_far false:
  /// any error is followed (a segment's lost heading is being found: there is none to
  /// protect). Never allocates.
  void add(const Eigen::Vector3d& axis_earth_upper, const Eigen::Vector3d& axis_earth_lower,
           double dt_s, bool refuse_far = true);
  /// Seconds followed since reset, each weighted as its error was (a horizontal axis: 1).
  double followed_s() const { return followed_s_; }
  /// Whether the caller should take the yaw now, at t_ns (at 10 Hz: pending_yaw.hpp).
  bool due(int64_t t_ns) { return pending_.due(t_ns); }
  /// The yaw by which the lower segment's heading should turn (relative to the upper's) since
  /// the last call, rad; the caller applies it (pending starts over).
  double take() { return pending_.take(); }
  /// Samples whose error was refused since the last call to take_refused().
  int take_refused();
  /// Starts over (the alignment was rebuilt).
  void reset();

 private:
  HingeHeadingOptions opt_;
  PendingYaw pending_;
  int refused_ = 0;
  double followed_s_ = 0;
};

}  // namespace mocap::rig
