// A hip's range holds its thigh's 6D heading (rig/range_heading.hpp): a thigh turned far beyond
// the hip's twist range is turned back to the range's margin, whatever the pelvis' heading; a
// joint inside the range, or beyond it by less than the margin, is left alone; a thigh lifted
// beyond its flexion range is no heading error.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "mocap/core/segments.hpp"
#include "mocap/core/units.hpp"
#include "mocap/rig/range_heading.hpp"
#include "mocap/skeleton/joint_limits.hpp"

namespace mocap::rig {
namespace {

Eigen::Quaterniond yaw(double deg) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(deg * kRadPerDeg, Eigen::Vector3d::UnitZ()));
}

const JointLimit& hip() {
  static const JointLimits limits = default_joint_limits();
  return limits.joint[index(Segment::thigh_l)];
}

/// Runs the hold at 100 Hz for `seconds` with the pelvis at `q_pelvis` and the thigh at
/// q_pelvis * yaw(twist0_deg) * q_pose; each 0.1 s the correction turns the thigh. Returns the
/// hip's twist left at the end, degrees; `turned_deg` the turn applied.
double run(double seconds, const Eigen::Quaterniond& q_pelvis, double twist0_deg,
           const Eigen::Quaterniond& q_pose, double& turned_deg) {
  RangeHeading hold;
  turned_deg = 0;
  for (int n = 1; n <= static_cast<int>(seconds * 100); ++n) {
    const Eigen::Quaterniond thigh = yaw(turned_deg) * q_pelvis * yaw(twist0_deg) * q_pose;
    hold.add(hip(), q_pelvis, thigh, 0.01);
    if (n % 10 == 0) turned_deg += hold.take() * kDegPerRad;
  }
  return twist0_deg + turned_deg;
}

TEST(RangeHeading, TurnsATwistFarBeyondTheRangeBackToItsMargin) {
  const RangeHeadingOptions o;
  double turned = 0;
  // Standing, the pelvis facing anywhere: the thigh 100 deg twisted out (the range ends at
  // 45, its margin at 65) and 100 deg in (-40, margin -60).
  for (double pelvis_deg : {0.0, 130.0}) {
    EXPECT_NEAR(run(10 * o.tau_s, yaw(pelvis_deg), 100, Eigen::Quaterniond::Identity(), turned),
                hip().twist_max_deg + o.margin_deg, 1.0)
        << pelvis_deg;
    EXPECT_NEAR(run(10 * o.tau_s, yaw(pelvis_deg), -100, Eigen::Quaterniond::Identity(), turned),
                hip().twist_min_deg - o.margin_deg, 1.0)
        << pelvis_deg;
  }
  // Within a time constant most of the way (1 - e^-1 of the 35 deg).
  run(o.tau_s, Eigen::Quaterniond::Identity(), 100, Eigen::Quaterniond::Identity(), turned);
  EXPECT_LT(turned, -0.55 * 35);
  EXPECT_GT(turned, -0.75 * 35);
}

TEST(RangeHeading, LeavesAJointWithinItsRangeOrMarginAlone) {
  double turned = 0;
  for (double twist : {0.0, 40.0, 60.0, -55.0}) {
    run(10, yaw(20), twist, Eigen::Quaterniond::Identity(), turned);
    EXPECT_EQ(turned, 0.0) << twist;
  }
}

TEST(RangeHeading, AThighLiftedBeyondItsFlexionRangeIsNoHeadingError) {
  // Flexion is about the thigh's left (y) axis; the range ends 125 deg forward: lifted 170 deg,
  // 45 beyond it. Turning the thigh's heading does not bring it back.
  const Eigen::Quaterniond lifted(Eigen::AngleAxisd(-170 * kRadPerDeg, Eigen::Vector3d::UnitY()));
  double turned = 0;
  run(10, yaw(20), 0, lifted, turned);
  EXPECT_EQ(turned, 0.0);
}

}  // namespace
}  // namespace mocap::rig
