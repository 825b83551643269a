// Procedural motions and the foot-planted root: smooth, start in the N-pose, feet do not slide.
#include <gtest/gtest.h>

#include <cmath>

#include "mocap/sim/motion.hpp"

namespace mocap::sim {
namespace {

double angle_deg(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return Eigen::AngleAxisd(a.conjugate() * b).angle() * 180 / M_PI;
}

TEST(Motion, EveryBuiltInStartsInTheNPoseAndIsFinite) {
  const auto dims = body_dimensions_from_height(1.75);
  const auto ref = reference_joint_positions(dims);
  for (auto name : motion_names()) {
    MotionTrack track(make_motion(name), dims, false);
    const auto [c0, c1] = track.motion().calibration_window_s();
    EXPECT_GE(c1 - c0, 2.9) << name;
    BodyPose pose;
    TruthFrame f;
    track.pose(0.5 * (c0 + c1), pose);
    truth_forward_kinematics(dims, pose, f);
    for (int i = 0; i < kSegmentCount; ++i) {
      EXPECT_LT(angle_deg(f.q_earth_segment[i], Eigen::Quaterniond::Identity()), 1e-9) << name;
      EXPECT_LT((f.p_earth_segment_m[i] - ref[i]).norm(), 1e-9) << name << " " << i;
    }
    for (double t = 0; t <= track.period_s(); t += 0.05) {
      track.pose(t, pose);
      truth_forward_kinematics(dims, pose, f);
      for (int i = 0; i < kSegmentCount; ++i) {
        ASSERT_TRUE(f.p_earth_segment_m[i].allFinite()) << name << " t=" << t;
        ASSERT_TRUE(f.q_earth_segment[i].coeffs().allFinite()) << name << " t=" << t;
      }
    }
  }
}

TEST(Motion, UnknownNameIsRejectedWithTheValidNames) {
  try {
    make_motion("moonwalk");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("moonwalk"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("walk"), std::string::npos);
  }
}

TEST(Motion, WalkAdvancesWithAPlantedStanceFoot) {
  const auto dims = body_dimensions_from_height(1.75);
  MotionTrack track(make_motion("walk"), dims, false);
  BodyPose pose;
  TruthFrame a, b;
  const double h = 0.01;
  int stance_checks = 0;
  for (double t = 4.0; t < 10.0; t += h) {
    track.pose(t, pose);
    truth_forward_kinematics(dims, pose, a);
    track.pose(t + h, pose);
    truth_forward_kinematics(dims, pose, b);
    const int l = index(Segment::foot_l), r = index(Segment::foot_r);
    const double dz = a.p_earth_segment_m[l].z() - a.p_earth_segment_m[r].z();
    if (std::abs(dz) < 0.03) continue;  // double support: weight is being handed over
    const int stance = dz < 0 ? l : r;
    const double v = (b.p_earth_segment_m[stance] - a.p_earth_segment_m[stance]).norm() / h;
    EXPECT_LT(v, 0.02) << "stance ankle slides at t=" << t;
    EXPECT_NEAR(a.p_earth_segment_m[stance].z(), 0.039 * 1.75, 0.005);
    ++stance_checks;
  }
  EXPECT_GT(stance_checks, 300);
  track.pose(track.period_s(), pose);
  // About 1 m/s over most of 8.8 s of walking, straight ahead (+x).
  EXPECT_GT(pose.p_earth_pelvis_m.x(), 5.0);
  EXPECT_LT(std::abs(pose.p_earth_pelvis_m.y()), 0.2);
}

TEST(Motion, LoopContinuesWhereThePreviousLoopEnded) {
  const auto dims = body_dimensions_from_height(1.75);
  MotionTrack track(make_motion("turn"), dims, true);
  BodyPose before, after;
  const double T = track.period_s();
  track.pose(T - 1e-6, before);
  track.pose(T + 1e-6, after);
  EXPECT_LT((before.p_earth_pelvis_m - after.p_earth_pelvis_m).norm(), 1e-4);
  EXPECT_LT(angle_deg(before.q_earth_pelvis, after.q_earth_pelvis), 1e-3);
  // After a second 180-degree turn the performer faces forward again.
  track.pose(2 * T, after);
  EXPECT_LT(angle_deg(after.q_earth_pelvis, Eigen::Quaterniond::Identity()), 1e-6);
}

}  // namespace
}  // namespace mocap::sim
