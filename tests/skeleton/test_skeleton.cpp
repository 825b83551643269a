// Skeleton solver: forward kinematics matches the body model, calibration is applied, untracked
// segments are interpolated, limits are reported or clamped, bad input never reaches the pose,
// output is deterministic.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "mocap/skeleton/skeleton.hpp"
#include "skeleton_test_util.hpp"

namespace mocap {
namespace {

using test::kMs;

Eigen::Vector3d pos(const PoseFrame& f, int s) {
  return Eigen::Vector3d(f.p_earth_segment_m[s][0], f.p_earth_segment_m[s][1],
                         f.p_earth_segment_m[s][2]);
}

TEST(Skeleton, NPoseMatchesReferencePositions) {
  const BodyModel model(BodyModelConfig{1.80});
  Skeleton sk(model, default_joint_limits(), RigMapping::full());
  for (int s = 0; s < kSegmentCount; ++s)
    sk.set_sensor_orientation(s, Eigen::Quaterniond::Identity(), 0);
  PoseFrame f;
  reset_pose(f);
  sk.solve(f);
  const auto ref = reference_joint_positions(model.dimensions());
  for (int s = 0; s < kSegmentCount; ++s) {
    EXPECT_LT((pos(f, s) - ref[s]).norm(), 1e-5) << kSegmentNames[s];
    EXPECT_EQ(f.segment_flags[s] & kSegTracked, kSegTracked);
    EXPECT_EQ(f.joint_violation_deg[s], 0);
  }
  EXPECT_EQ(f.flags & kFrameCalibrated, 0u);
}

TEST(Skeleton, ForwardKinematicsFollowsSensorsThroughCalibration) {
  std::mt19937 rng(11);
  const BodyModel model;
  std::array<Eigen::Quaterniond, kSegmentCount> mount;
  for (auto& q : mount)
    q = test::random_rotation(rng);
  Calibration c;
  c.valid = true;
  for (int s = 0; s < kSegmentCount; ++s) {
    c.calibrated[s] = true;
    c.q_sensor_segment[s] = mount[s];
  }
  Skeleton sk(model, default_joint_limits(), RigMapping::full());
  sk.set_calibration(c);
  const auto pose = test::random_pose(rng, 40);
  for (int s = 0; s < kSegmentCount; ++s)
    sk.set_sensor_orientation(s, pose[s] * mount[s].conjugate(), 100 * kMs);
  PoseFrame f;
  reset_pose(f);
  sk.solve(f);
  EXPECT_EQ(f.flags & kFrameCalibrated, uint32_t{kFrameCalibrated});
  EXPECT_EQ(f.t_ns, 100 * kMs);
  for (int s = 0; s < kSegmentCount; ++s) {
    EXPECT_LT(angle_between_deg(sk.q_earth_segment()[s], pose[s]), 1e-6);
    const int p = kSegmentParent[s];
    if (p < 0) continue;
    // Position: parent position + parent orientation * joint offset (thesis Fig. 29).
    const Eigen::Vector3d expect = sk.p_earth_segment_m()[p] + pose[p] * model.joint_offset_m(s);
    EXPECT_LT((sk.p_earth_segment_m()[s] - expect).norm(), 1e-9);
    EXPECT_LT(angle_between_deg(sk.q_parent_segment()[s], pose[p].conjugate() * pose[s]), 1e-6);
    EXPECT_LT(angle_between_deg(from_wxyz(f.q_parent_segment[s]), pose[p].conjugate() * pose[s]),
              0.01);
  }
}

TEST(Skeleton, UntrackedSegmentsAreInterpolatedOrFollowTheParent) {
  RigMapping rig = RigMapping::full();
  rig.sensor_for_segment[index(Segment::torso)] = -1;
  rig.sensor_for_segment[index(Segment::hand_l)] = -1;
  Skeleton sk(BodyModel{}, default_joint_limits(), rig);
  const Eigen::Quaterniond bent = axis_rotation(1, 60 * kRadPerDeg);
  for (int s = 0; s < kSegmentCount; ++s)
    sk.set_sensor_orientation(
        s,
        s == index(Segment::neck) || s == index(Segment::head) || s == index(Segment::forearm_l)
            ? bent
            : Eigen::Quaterniond::Identity(),
        0);
  PoseFrame f;
  sk.solve(f);
  const int torso = index(Segment::torso);
  EXPECT_LT(angle_between_deg(sk.q_earth_segment()[torso], axis_rotation(1, 30 * kRadPerDeg)),
            1e-9);
  EXPECT_EQ(f.segment_flags[torso] & kSegInferred, uint32_t{kSegInferred});
  EXPECT_LT(angle_between_deg(sk.q_earth_segment()[index(Segment::hand_l)], bent), 1e-9);
  EXPECT_EQ(f.segment_flags[index(Segment::pelvis)] & kSegTracked, uint32_t{kSegTracked});
}

// Limits are reported, never imposed: the pose follows the sensors.
TEST(Skeleton, ReportsViolationsWithoutChangingThePose) {
  {
    SkeletonOptions o;
    Skeleton sk(BodyModel{}, default_joint_limits(), RigMapping::full(), o);
    for (int s = 0; s < kSegmentCount; ++s)
      sk.set_sensor_orientation(s, Eigen::Quaterniond::Identity(), 0);
    // Knee bent forward by 35 deg: 30 deg beyond the 5 deg hyperextension.
    sk.set_sensor_orientation(index(Segment::shank_l), axis_rotation(1, -35 * kRadPerDeg), 0);
    PoseFrame f;
    sk.solve(f);
    const int k = index(Segment::shank_l);
    EXPECT_NEAR(f.joint_violation_deg[k], 30, 1e-3);
    EXPECT_TRUE(f.segment_flags[k] & kSegLimitViolated);
    EXPECT_EQ(f.joint_violation_deg[index(Segment::shank_r)], 0);
    EXPECT_NEAR(angle_between_deg(sk.q_earth_segment()[k], axis_rotation(1, -35 * kRadPerDeg)), 0,
                1e-6);
    // The drift signal accumulates while the violation persists.
    for (int t = 1; t <= 200; ++t) {
      sk.set_sensor_orientation(k, axis_rotation(1, -35 * kRadPerDeg), t * 20 * kMs);
      sk.solve(f);
    }
    EXPECT_GT(sk.drift_signal_deg(), 20);
    EXPECT_LT(sk.drift_signal_deg(), 30.001);
  }
}

TEST(Skeleton, RejectsNonFiniteInputAndFlagsStaleSensors) {
  Skeleton sk(BodyModel{}, default_joint_limits(), RigMapping::full());
  for (int s = 0; s < kSegmentCount; ++s)
    sk.set_sensor_orientation(s, Eigen::Quaterniond::Identity(), 0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  sk.set_sensor_orientation(3, Eigen::Quaterniond(nan, 0, 0, 0), 10 * kMs);
  sk.set_sensor_orientation(4, Eigen::Quaterniond(0, 0, 0, 0), 10 * kMs);
  sk.set_sensor_orientation(99, Eigen::Quaterniond::Identity(), 10 * kMs);
  EXPECT_EQ(sk.rejected_samples(), 3u);
  for (int s = 0; s < kSegmentCount; ++s)
    if (s != 7) sk.set_sensor_orientation(s, Eigen::Quaterniond::Identity(), 500 * kMs);
  PoseFrame f;
  sk.solve(f);
  for (int s = 0; s < kSegmentCount; ++s) {
    for (float v : f.q_earth_segment[s])
      EXPECT_TRUE(std::isfinite(v));
    for (float v : f.p_earth_segment_m[s])
      EXPECT_TRUE(std::isfinite(v));
  }
  EXPECT_TRUE(f.segment_flags[7] & kSegStale);
  EXPECT_FALSE(f.segment_flags[6] & kSegStale);
}

TEST(Skeleton, SilentSensorIsInferredAndHeadingResetFacesTarget) {
  Skeleton sk(BodyModel{}, default_joint_limits(), RigMapping::full());
  const Eigen::Quaterniond facing = yaw_rotation(50 * kRadPerDeg);
  for (int s = 0; s < kSegmentCount; ++s)
    sk.set_sensor_orientation(s, facing, 0);
  sk.set_sensor_orientation(index(Segment::hand_r), axis_rotation(0, 1.0), 0);
  sk.set_sensor_live(index(Segment::hand_r), false);
  PoseFrame f;
  sk.solve(5 * kMs, f);
  EXPECT_EQ(f.t_ns, 5 * kMs);
  EXPECT_TRUE(f.segment_flags[index(Segment::hand_r)] & kSegInferred);
  EXPECT_LT(angle_between_deg(sk.q_earth_segment()[index(Segment::hand_r)], facing), 1e-9);
  sk.set_sensor_live(index(Segment::hand_r), true);
  sk.solve(f);
  EXPECT_TRUE(f.segment_flags[index(Segment::hand_r)] & kSegTracked);
  // The inputs as a heading reset reads them (rig/alignment.hpp): live ones only.
  sk.set_sensor_live(index(Segment::hand_r), false);
  EXPECT_FALSE(sk.sensor_live(index(Segment::hand_r)));
  EXPECT_TRUE(sk.sensor_live(index(Segment::pelvis)));
  EXPECT_LT(angle_between_deg(sk.sensor_orientation(index(Segment::pelvis)), facing), 1e-12);
}

// An alignment found while tracking (set_calibration with ease) turns the published segment
// onto it at ease_deg_s, never in one frame, from where it was; a new calibration applies at
// once; a non-finite calibration never reaches the pose.
TEST(Skeleton, AnAlignmentFoundWhileTrackingIsEasedInNeverInOneFrame) {
  std::mt19937 rng(13);
  const int thigh = index(Segment::thigh_l);
  Calibration c;
  c.valid = true;
  for (int s = 0; s < kSegmentCount; ++s) {
    c.calibrated[s] = true;
    c.q_sensor_segment[s] = test::random_rotation(rng);
  }
  Calibration turned = c;  // the thigh's sensor frame found 150 deg off in heading
  turned.q_correction[thigh] =
      Eigen::Quaterniond(Eigen::AngleAxisd(150 * kRadPerDeg, Eigen::Vector3d::UnitZ()));
  Skeleton sk(BodyModel{}, default_joint_limits(), RigMapping::full());
  const double ease_deg_s = sk.options().ease_deg_s;
  ASSERT_GT(ease_deg_s, 0);
  sk.set_calibration(c);
  const auto pose = test::random_pose(rng, 40);
  PoseFrame f;
  reset_pose(f);
  auto solve_at = [&](int64_t t_ns) {
    for (int s = 0; s < kSegmentCount; ++s)
      sk.set_sensor_orientation(s, pose[s], t_ns);
    sk.solve(t_ns, f);
    return sk.q_earth_segment()[thigh];
  };
  const Eigen::Quaterniond before = solve_at(0);
  const Eigen::Quaterniond target = turned.segment_from_sensor(thigh, pose[thigh]);
  ASSERT_GT(angle_between_deg(before, target), 140);
  sk.set_calibration(turned, /*ease=*/true);
  Eigen::Quaterniond last = before;
  int frames = 0;
  for (int k = 1; k <= 100; ++k) {
    const Eigen::Quaterniond q = solve_at(k * 10 * kMs);
    EXPECT_LE(angle_between_deg(q, last), ease_deg_s * 0.01 + 1e-6) << "frame " << k;
    last = q;
    if (angle_between_deg(q, target) > 1e-6) frames = k;
  }
  // 150 deg at ease_deg_s, then exactly the new calibration; the other segments never moved.
  EXPECT_EQ(frames, static_cast<int>(std::ceil(150.0 / (ease_deg_s * 0.01))) - 1);
  EXPECT_LT(angle_between_deg(last, target), 1e-6);
  for (int s = 0; s < kSegmentCount; ++s) {
    if (s == thigh) continue;
    EXPECT_LT(angle_between_deg(sk.q_earth_segment()[s], c.segment_from_sensor(s, pose[s])), 1e-6);
  }
  // Not eased: at once (a new calibration, a heading reset).
  sk.set_calibration(c);
  EXPECT_LT(angle_between_deg(solve_at(2000 * kMs), c.segment_from_sensor(thigh, pose[thigh])),
            1e-6);
  // A calibration gone non-finite is rejected by the ease, never published as NaN.
  Calibration bad = c;
  bad.q_correction[thigh].coeffs().setConstant(std::numeric_limits<double>::quiet_NaN());
  sk.set_calibration(bad, true);
  sk.set_calibration(c, true);
  EXPECT_TRUE(solve_at(2010 * kMs).coeffs().allFinite());
}

TEST(Skeleton, DeterministicBitIdenticalFrames) {
  std::mt19937 rng(12);
  std::vector<std::array<Eigen::Quaterniond, kSegmentCount>> poses;
  for (int k = 0; k < 50; ++k)
    poses.push_back(test::random_pose(rng, 70));
  auto run = [&](std::vector<PoseFrame>& out) {
    Skeleton sk(BodyModel{}, default_joint_limits(), RigMapping::full());
    for (size_t k = 0; k < poses.size(); ++k) {
      for (int s = 0; s < kSegmentCount; ++s)
        sk.set_sensor_orientation(s, poses[k][s], static_cast<int64_t>(k) * 10 * kMs);
      PoseFrame f;
      reset_pose(f);
      sk.solve(f);
      out.push_back(f);
    }
  };
  std::vector<PoseFrame> a, b;
  run(a);
  run(b);
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k)
    EXPECT_EQ(std::memcmp(&a[k], &b[k], sizeof(PoseFrame)), 0);
}

}  // namespace
}  // namespace mocap
