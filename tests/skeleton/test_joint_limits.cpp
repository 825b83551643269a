// Joint limits: anatomical poses pass, impossible ones are reported by how much, clamping lands
// on the boundary, right mirrors left, TOML overrides.
#include <gtest/gtest.h>

#include "mocap/skeleton/joint_limits.hpp"
#include "mocap/skeleton/quat_math.hpp"
#include "skeleton_test_util.hpp"

namespace mocap {
namespace {

Eigen::Quaterniond rot(int axis, double deg) {
  return axis_rotation(axis, deg * kRadPerDeg);
}

TEST(JointLimits, DefaultsAreValidAndMirrored) {
  const JointLimits L = default_joint_limits();
  EXPECT_NO_THROW(validate(L));
  EXPECT_FALSE(L.joint[0].limited);
  for (int i = 1; i < kSegmentCount; ++i)
    EXPECT_TRUE(L.joint[i].limited) << kJointNames[i];
  EXPECT_TRUE(L.joint[index(Segment::shank_l)].hinge);
  EXPECT_TRUE(L.joint[index(Segment::forearm_r)].hinge);
  // Mirror: a left rotation reflected (x and z angles negated) checks the same on the right.
  std::mt19937 rng(7);
  for (int k = 0; k < 200; ++k) {
    const Eigen::Quaterniond q = test::random_small_rotation(rng, 150);
    const Eigen::Quaterniond m(q.w(), -q.x(), q.y(), -q.z());
    for (auto [l, r] : {std::pair{Segment::upper_arm_l, Segment::upper_arm_r},
                        std::pair{Segment::thigh_l, Segment::thigh_r},
                        std::pair{Segment::foot_l, Segment::foot_r},
                        std::pair{Segment::forearm_l, Segment::forearm_r}}) {
      EXPECT_NEAR(check_joint(L.joint[index(l)], q).violation_deg,
                  check_joint(L.joint[index(r)], m).violation_deg, 1e-9);
    }
  }
}

TEST(JointLimits, AnatomicalPosesPassImpossibleOnesViolate) {
  const JointLimits L = default_joint_limits();
  auto v = [&](Segment s, const Eigen::Quaterniond& q) {
    return check_joint(L.joint[index(s)], q).violation_deg;
  };
  // Elbow flexed 90 deg (forearm forward) with 40 deg pronation: fine.
  EXPECT_EQ(v(Segment::forearm_l, rot(1, -90) * rot(2, 40)), 0);
  // Elbow hyperextended 30 deg: 25 deg beyond the 5 deg allowance.
  EXPECT_NEAR(v(Segment::forearm_l, rot(1, 30)), 25, 1e-9);
  // Elbow bent sideways 30 deg: 20 deg beyond the 10 deg off-axis tolerance.
  EXPECT_NEAR(v(Segment::forearm_r, rot(0, 30)), 20, 1e-9);
  // Knee flexed 90 (shank back): fine; knee bent forward 20: 15 deg violation.
  EXPECT_EQ(v(Segment::shank_r, rot(1, 90)), 0);
  EXPECT_NEAR(v(Segment::shank_r, rot(1, -20)), 15, 1e-9);
  // Hip flexed 90 forward: fine; 60 deg backwards: 30 beyond extension.
  EXPECT_EQ(v(Segment::thigh_l, rot(1, -90)), 0);
  EXPECT_NEAR(v(Segment::thigh_l, rot(1, 60)), 30, 1e-9);  // extension limit 30
  // Shoulder abducted to T-pose: left +90 about x, right -90 about x; the wrong way is adduction.
  EXPECT_EQ(v(Segment::upper_arm_l, rot(0, 90)), 0);
  EXPECT_EQ(v(Segment::upper_arm_r, rot(0, -90)), 0);
  EXPECT_NEAR(v(Segment::upper_arm_l, rot(0, -90)), 45, 1e-9);  // adduction limit 45
  // Head turned 120 deg: twist beyond 45.
  EXPECT_NEAR(v(Segment::head, rot(2, 120)), 75, 1e-9);
  // Twist and swing combined: swing inside, twist out.
  const JointCheck c = check_joint(L.joint[index(Segment::thigh_l)], rot(1, -30) * rot(2, 60));
  EXPECT_NEAR(c.twist_deg, 60, 1e-9);
  EXPECT_NEAR(c.b_deg, -30, 1e-9);
  EXPECT_NEAR(c.violation_deg, 15, 1e-9);
}

TEST(JointLimits, ClampLandsInsideAndKeepsAllowedRotations) {
  const JointLimits L = default_joint_limits();
  std::mt19937 rng(8);
  for (int k = 0; k < 500; ++k) {
    const int s = 1 + k % (kSegmentCount - 1);
    const Eigen::Quaterniond q = test::random_rotation(rng);
    Eigen::Quaterniond qc;
    const JointCheck c = check_joint(L.joint[s], q, &qc);
    const JointCheck after = check_joint(L.joint[s], qc);
    EXPECT_LT(after.violation_deg, 1e-6) << kJointNames[s];
    if (!c.violated) {
      EXPECT_EQ(qc.coeffs(), q.coeffs());
    } else {
      EXPECT_NEAR(angle_between_deg(q, qc), c.violation_deg, 1e-9);
      EXPECT_GT(c.violation_deg, 0);
    }
  }
}

TEST(JointLimits, TomlOverridesAndErrors) {
  const JointLimits L =
      parse_joint_limits("[joint.knee_l]\nb_deg = [0, 120]\n[joint.neck]\nhinge = false\n");
  EXPECT_EQ(L.joint[index(Segment::shank_l)].b_max_deg, 120);
  EXPECT_EQ(L.joint[index(Segment::shank_r)].b_max_deg, 150);
  auto err = [](std::string_view t) {
    try {
      parse_joint_limits(t, "lim.toml");
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(err("[joint.knee_x]\n").find("lim.toml:1:"), std::string::npos);
  EXPECT_NE(err("[joint.knee_l]\nb_deg = [10, 120]\n").find("min <= 0"), std::string::npos);
  EXPECT_NE(err("[joint.knee_l]\nb_deg = [0]\n").find("[min, max]"), std::string::npos);
  EXPECT_NE(err("[joint.elbow_r]\nfoo = 1\n").find("unknown key 'foo'"), std::string::npos);
}

}  // namespace
}  // namespace mocap
