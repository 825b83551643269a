// Root motion: a walking body advances by its step lengths with the stance foot planted and the
// lowest contact point on the floor; a pinned root stays put.
#include <gtest/gtest.h>

#include "mocap/skeleton/skeleton.hpp"
#include "skeleton_test_util.hpp"

namespace mocap {
namespace {

// Walking gait: per half cycle (phase u in 0..1) the stance leg swings straight from +A (hip
// flexed) to -A, the swing leg from -A to +A with the knee bent so its foot stays clear; feet
// stay flat. Walks along the earth direction `heading_rad`.
std::array<Eigen::Quaterniond, kSegmentCount> gait_pose(double t_half_cycles, double heading_rad) {
  const double amp = 20 * kRadPerDeg;
  const int half = static_cast<int>(std::floor(t_half_cycles));
  const double u = t_half_cycles - half;
  const bool left_stance = half % 2 == 0;
  const double th_stance = amp * (1 - 2 * u);
  const double th_swing = -th_stance;
  const double knee = std::max(60 * kRadPerDeg * std::sin(M_PI * u),
                               2 * th_swing + 8 * kRadPerDeg * std::sin(M_PI * u));
  std::array<Eigen::Quaterniond, kSegmentCount> j;
  j.fill(Eigen::Quaterniond::Identity());
  j[0] = yaw_rotation(heading_rad);
  const int st = left_stance ? index(Segment::thigh_l) : index(Segment::thigh_r);
  const int sw = left_stance ? index(Segment::thigh_r) : index(Segment::thigh_l);
  j[st] = axis_rotation(1, -th_stance);
  j[sw] = axis_rotation(1, -th_swing);
  j[sw + 1] = axis_rotation(1, knee);
  // Flat feet: undo the leg's rotation at the ankle.
  j[st + 2] = j[st].conjugate();
  j[sw + 2] = (j[sw] * j[sw + 1]).conjugate();
  // Arms swing opposite to the legs.
  j[index(Segment::upper_arm_l)] = axis_rotation(1, (left_stance ? -1 : 1) * th_stance * 0.7);
  j[index(Segment::upper_arm_r)] = axis_rotation(1, (left_stance ? 1 : -1) * th_stance * 0.7);
  return test::earth_from_joints(j);
}

TEST(RootMotion, WalkingAdvancesByTheStepLengths) {
  const BodyModel model;
  Skeleton sk(model, default_joint_limits(), RigMapping::full());
  const double heading = 30 * kRadPerDeg;
  const int steps = 8, per_step = 100;
  PoseFrame f;
  Eigen::Vector3d start;
  int planted_frames = 0;
  int prev_stance = -1;
  Eigen::Vector3d prev_ankle = Eigen::Vector3d::Zero();
  double worst_slide = 0, worst_floor = 0;
  for (int k = 0; k <= steps * per_step; ++k) {
    const auto pose = gait_pose(static_cast<double>(k) / per_step, heading);
    for (int s = 0; s < kSegmentCount; ++s)
      sk.set_sensor_orientation(s, pose[s], k * 10'000'000LL);
    sk.solve(f);
    const auto& p = sk.p_earth_segment_m();
    if (k == 0) start = p[0];
    const int stance = (f.segment_flags[index(Segment::foot_l)] & kSegStance)
                           ? index(Segment::foot_l)
                           : index(Segment::foot_r);
    EXPECT_NE(f.segment_flags[stance] & kSegStance, 0u);
    if (stance == prev_stance) {
      worst_slide = std::max(worst_slide, (p[stance] - prev_ankle).head<2>().norm());
      ++planted_frames;
    }
    prev_stance = stance;
    prev_ankle = p[stance];
    // Lowest contact point on the floor.
    double zmin = 1e9;
    for (int foot : {index(Segment::foot_l), index(Segment::foot_r)}) {
      const Eigen::Vector3d e = model.end_offset_m(foot);
      zmin = std::min({zmin, (p[foot] + sk.q_earth_segment()[foot] * e).z(),
                       (p[foot] + sk.q_earth_segment()[foot] * Eigen::Vector3d(0, 0, e.z())).z()});
    }
    worst_floor = std::max(worst_floor, std::abs(zmin));
  }
  const double leg_m =
      model.bone_length_m(index(Segment::shank_l)) + model.bone_length_m(index(Segment::foot_l));
  const double expected = steps * 2 * leg_m * std::sin(20 * kRadPerDeg);
  const Eigen::Vector3d travel = sk.p_earth_segment_m()[0] - start;
  EXPECT_NEAR(travel.head<2>().norm(), expected, 0.03 * expected);
  // In the walking direction.
  EXPECT_NEAR(std::atan2(travel.y(), travel.x()), heading, 0.02);
  EXPECT_LT(worst_slide, 1e-9);
  EXPECT_GT(planted_frames, steps * per_step * 9 / 10);
  EXPECT_LT(worst_floor, 1e-9);
}

TEST(RootMotion, PinnedRootStays) {
  SkeletonOptions o;
  o.root.pinned = true;
  const BodyModel model;
  Skeleton sk(model, default_joint_limits(), RigMapping::full(), o);
  PoseFrame f;
  for (int k = 0; k < 300; ++k) {
    const auto pose = gait_pose(k / 100.0, 0);
    for (int s = 0; s < kSegmentCount; ++s)
      sk.set_sensor_orientation(s, pose[s], k * 10'000'000LL);
    sk.solve(f);
    EXPECT_EQ(sk.p_earth_segment_m()[0], Eigen::Vector3d(0, 0, model.pelvis_height_m()));
    EXPECT_EQ(f.segment_flags[index(Segment::foot_l)] & kSegStance, 0u);
  }
}

}  // namespace
}  // namespace mocap
