// Slerp, pose interpolation, dropout bridging, fixed-rate resampling, two-bone IK.
#include <gtest/gtest.h>

#include "mocap/skeleton/ik.hpp"
#include "mocap/skeleton/interpolation.hpp"
#include "mocap/skeleton/joint_limits.hpp"
#include "skeleton_test_util.hpp"

namespace mocap {
namespace {

using test::kMs;

TEST(Slerp, ShortestPathConstantSpeed) {
  std::mt19937 rng(41);
  for (int k = 0; k < 200; ++k) {
    const Eigen::Quaterniond a = test::random_rotation(rng), b = test::random_rotation(rng);
    Eigen::Quaterniond bn = b;
    bn.coeffs() = -b.coeffs();  // same rotation, other hemisphere
    const double total = angle_between_deg(a, b);
    EXPECT_LE(total, 180.0);
    for (double t : {0.0, 0.25, 0.5, 0.9, 1.0}) {
      const Eigen::Quaterniond q = slerp_shortest(a, bn, t);
      EXPECT_NEAR(angle_between_deg(a, q), t * total, 1e-6);
      EXPECT_NEAR(angle_between_deg(q, b), (1 - t) * total, 1e-6);
    }
  }
}

TEST(Interpolation, TrackBridgesShortDropoutsOnly) {
  OrientationTrack tr(50 * kMs, 500 * kMs);
  EXPECT_FALSE(tr.sample(0).valid);
  for (int k = 0; k <= 10; ++k)
    tr.push(k * 10 * kMs, axis_rotation(2, k * 0.01));
  // 200 ms dropout, then 1 s dropout.
  tr.push(300 * kMs, axis_rotation(2, 0.30));
  tr.push(1300 * kMs, axis_rotation(2, 1.30));
  EXPECT_FALSE(tr.push(1300 * kMs, Eigen::Quaterniond::Identity()));  // not newer
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(tr.push(1400 * kMs, Eigen::Quaterniond(nan, 0, 0, 0)));
  auto s = tr.sample(55 * kMs);
  EXPECT_FALSE(s.bridged);
  EXPECT_NEAR(yaw_of_rad(s.q), 0.055, 1e-9);
  s = tr.sample(200 * kMs);
  EXPECT_TRUE(s.bridged);
  EXPECT_NEAR(yaw_of_rad(s.q), 0.20, 1e-9);
  s = tr.sample(800 * kMs);  // too long a gap: hold
  EXPECT_TRUE(s.held);
  EXPECT_NEAR(yaw_of_rad(s.q), 0.30, 1e-9);
  s = tr.sample(2000 * kMs);
  EXPECT_TRUE(s.held);
  EXPECT_NEAR(yaw_of_rad(s.q), 1.30, 1e-9);
  // bridged(): the same verdict and orientation as sample(), at keys, in gaps, outside.
  int bridged_count = 0;
  for (int64_t t = -10 * kMs; t <= 2100 * kMs; t += 5 * kMs) {
    const auto smp = tr.sample(t);
    Eigen::Quaterniond q(0, 0, 0, 0);
    ASSERT_EQ(tr.bridged(t, q), smp.bridged) << t;
    if (!smp.bridged) continue;
    ++bridged_count;
    EXPECT_EQ(q.coeffs(), smp.q.coeffs()) << t;
  }
  EXPECT_EQ(bridged_count, 39);  // 105..295 ms: the 200 ms gap
  // Capacity: the oldest keys drop out.
  for (int k = 0; k < 2 * OrientationTrack::kCapacity; ++k)
    tr.push((2000 + k) * kMs, Eigen::Quaterniond::Identity());
  EXPECT_EQ(tr.size(), OrientationTrack::kCapacity);
}

TEST(Interpolation, ResamplerProducesFixedRate) {
  PoseResampler rs(100.0);
  PoseFrame out;
  int64_t t = 0;
  std::vector<PoseFrame> got;
  std::mt19937 rng(42);
  std::uniform_int_distribution<int> jitter(3, 17);
  while (t < 1000 * kMs) {
    PoseFrame f;
    reset_pose(f);
    f.t_ns = t;
    // Root yaw and x position proportional to time: interpolation must reproduce them.
    f.q_earth_segment[0] = to_wxyz(yaw_rotation(static_cast<double>(t) * 1e-9));
    f.p_earth_segment_m[0] = {static_cast<float>(t * 1e-9), 0, 1};
    rs.push(f);
    while (rs.next(out))
      got.push_back(out);
    t += jitter(rng) * kMs;
  }
  ASSERT_GT(got.size(), 90u);
  for (size_t k = 0; k < got.size(); ++k) {
    EXPECT_EQ(got[k].t_ns, static_cast<int64_t>(k) * 10 * kMs);
    EXPECT_EQ(got[k].frame, k);
    const double ts = static_cast<double>(got[k].t_ns) * 1e-9;
    EXPECT_NEAR(yaw_of_rad(from_wxyz(got[k].q_earth_segment[0])), ts, 1e-5);
    EXPECT_NEAR(got[k].p_earth_segment_m[0][0], ts, 1e-5);
  }
}

TEST(Ik, TwoBoneReachesAndBendsTowardsHint) {
  const Eigen::Vector3d root(0, 0, 1);
  const TwoBoneIk r =
      solve_two_bone_ik(root, 0.4, 0.4, Eigen::Vector3d(0.1, 0, 0.4), Eigen::Vector3d::UnitX());
  EXPECT_TRUE(r.reached);
  EXPECT_NEAR((r.p_mid_m - root).norm(), 0.4, 1e-12);
  EXPECT_NEAR((r.p_end_m - r.p_mid_m).norm(), 0.4, 1e-12);
  EXPECT_LT((r.p_end_m - Eigen::Vector3d(0.1, 0, 0.4)).norm(), 1e-12);
  EXPECT_GT(r.p_mid_m.x(), 0.1);  // knee forward
  const TwoBoneIk far =
      solve_two_bone_ik(root, 0.4, 0.4, Eigen::Vector3d(0, 0, -1), Eigen::Vector3d::UnitX());
  EXPECT_FALSE(far.reached);
  EXPECT_LT((far.p_end_m - Eigen::Vector3d(0, 0, 0.2)).norm(), 1e-12);
}

TEST(Ik, LimbIkGivesPureHingeFlexionWithinLimits) {
  const BodyModel model;
  const JointLimits lim = default_joint_limits();
  std::mt19937 rng(43);
  std::uniform_real_distribution<double> u(-0.25, 0.25);
  for (Segment upper :
       {Segment::thigh_l, Segment::thigh_r, Segment::upper_arm_l, Segment::upper_arm_r}) {
    const int s = index(upper);
    const bool leg = upper == Segment::thigh_l || upper == Segment::thigh_r;
    const Eigen::Vector3d hint(leg ? 1.0 : -1.0, 0, 0);
    for (int k = 0; k < 50; ++k) {
      const Eigen::Vector3d root(0, 0, 1);
      // Anywhere below the joint, 55..98 % of the limb's reach (flexion up to ~115 deg).
      const double reach = model.bone_length_m(s + 1) + model.bone_length_m(s + 2);
      const Eigen::Vector3d dir = Eigen::Vector3d(u(rng), u(rng), -0.5).normalized();
      const double frac = 0.55 + 0.43 * (u(rng) + 0.25) * 2;
      const Eigen::Vector3d target = root + dir * frac * reach;
      std::array<Eigen::Quaterniond, kSegmentCount> q;
      q.fill(Eigen::Quaterniond::Identity());
      const TwoBoneIk r = solve_limb_ik(model, upper, root, target, hint, q);
      ASSERT_TRUE(r.reached);
      // Forward kinematics with the resulting orientations reaches the target.
      const Eigen::Vector3d mid = root + q[s] * model.joint_offset_m(s + 1);
      const Eigen::Vector3d end = mid + q[s + 1] * model.joint_offset_m(s + 2);
      EXPECT_LT((end - target).norm(), 1e-9);
      // The middle joint is a pure rotation about y with the anatomical sign.
      const JointCheck c = check_joint(lim.joint[s + 1], q[s].conjugate() * q[s + 1]);
      EXPECT_NEAR(c.a_deg, 0, 1e-6);
      EXPECT_NEAR(c.twist_deg, 0, 1e-6);
      EXPECT_EQ(c.violation_deg, 0) << kSegmentNames[s + 1] << " b=" << c.b_deg;
    }
  }
}

}  // namespace
}  // namespace mocap
