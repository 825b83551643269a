// 6D rigs: a ball joint's range of motion as evidence of its child segment's heading. A 6D
// filter's heading is its own, and a few clipped gyro samples (a kick, a jump: CMU 01_12's
// left leg at 18 s, its gyros at full scale) lose tens of degrees of it at once; the knee's
// hinge (hinge_heading.hpp) then only makes the thigh and the shank agree with each other, not
// with the pelvis. A hip turned 70 deg about the thigh's long axis is no pose a person makes:
// a joint beyond its range (skeleton/joint_limits.hpp) by more than margin_deg, the spread of
// people's ranges and of the model's, says the child's heading is off by the yaw that takes it
// back to that margin (a joint's range of motion as a heading constraint: Lehmann, Laidig,
// Deimel, Seel, arXiv:2002.00639). It is taken only where a turn about the vertical is what brings
// the joint back (a thigh lifted beyond its flexion range is a tilt or a real pose, not a heading),
// and integrated with time constant tau_s like the hinge's hold; the caller turns the child.
// The body tracker holds the hips only. Measured on CMU 6D (scripts/accuracy-report, 24 clips x
// 3 seeds): without the margin a real hip beyond the table's 45 deg for seconds (01_14) turned
// its thigh 8 deg; every ball joint held with no margin turned a hand 37 deg off (ordinary clips
// reach beyond the wrists' table ranges as the performer maps them).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>

#include "mocap/rig/pending_yaw.hpp"
#include "mocap/skeleton/joint_limits.hpp"

namespace mocap::rig {

struct RangeHeadingOptions {
  double tau_s = 2.0;        ///< time constant of the correction, seconds
  double margin_deg = 20.0;  ///< beyond the joint's range by less than this: no evidence
};

class RangeHeading {
 public:
  explicit RangeHeading(RangeHeadingOptions o = {}) : opt_(o) {}

  /// One sample: the joint's limit, the parent's and the child's segment orientations in the
  /// earth frame as they are aligned now; dt_s since the last sample. Never allocates.
  void add(const JointLimit& limit, const Eigen::Quaterniond& q_earth_parent,
           const Eigen::Quaterniond& q_earth_child, double dt_s);
  /// Whether the caller should take the yaw now, at t_ns (at 10 Hz: pending_yaw.hpp).
  bool due(int64_t t_ns) { return pending_.due(t_ns); }
  /// The yaw by which the child's heading should turn since the last call, rad; the caller
  /// applies it (pending starts over).
  double take() { return pending_.take(); }
  /// Starts over (the alignment was rebuilt).
  void reset() { pending_.reset(); }

 private:
  RangeHeadingOptions opt_;
  PendingYaw pending_;
};

}  // namespace mocap::rig
