// Avatar geometry: capsules follow the pose, flags tint segments, NaN poses draw nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "mocap/viewer/avatar_geometry.hpp"
#include "mocap/viewer/pose_source.hpp"

namespace mocap::viewer {
namespace {

Eigen::Vector3f a_of(const CapsuleInstance& c) {
  return {c.a_m[0], c.a_m[1], c.a_m[2]};
}
Eigen::Vector3f b_of(const CapsuleInstance& c) {
  return {c.b_m[0], c.b_m[1], c.b_m[2]};
}

TEST(AvatarGeometry, NPoseCapsulesStandOnTheFloorInHumanOrder) {
  const BodyDimensions dims = body_dimensions_from_height(1.75);
  const PoseFrame f = reference_pose(dims, Eigen::Vector3f(2, -1, 0));
  std::vector<CapsuleInstance> caps;
  append_avatar(f, dims, AvatarStyle{}, caps);
  ASSERT_EQ(caps.size(), static_cast<size_t>(kSegmentCount + 2));  // + hip and shoulder bars
  const auto& head = caps[index(Segment::head)];
  const auto& torso = caps[index(Segment::torso)];
  const auto& foot = caps[index(Segment::foot_l)];
  EXPECT_GT(std::min(head.a_m[2], head.b_m[2]), std::max(torso.a_m[2], torso.b_m[2]) - 0.01f);
  EXPECT_NEAR(head.b_m[2] + head.radius_m, 1.75f, 0.12f) << "top of the head near body height";
  EXPECT_NEAR(std::min(foot.a_m[2], foot.b_m[2]) - foot.radius_m, 0.0f, 0.01f)
      << "the sole touches the floor";
  // The avatar stands where it was put, and its left arm is on the +y side (facing +x).
  EXPECT_NEAR(torso.a_m[0], 2.0f, 0.05f);
  EXPECT_NEAR(torso.a_m[1], -1.0f, 0.05f);
  EXPECT_GT(caps[index(Segment::upper_arm_l)].a_m[1], caps[index(Segment::upper_arm_r)].a_m[1]);
}

TEST(AvatarGeometry, CapsulesRotateWithTheSegment) {
  const BodyDimensions dims = body_dimensions_from_height(1.75);
  std::array<Eigen::Quaternionf, kSegmentCount> q;
  q.fill(Eigen::Quaternionf::Identity());
  // Left upper arm raised forward to horizontal: rotation about y by -90 deg.
  q[index(Segment::upper_arm_l)] = Eigen::AngleAxisf(-1.5707963f, Eigen::Vector3f::UnitY());
  PoseFrame f;
  reset_pose(f);
  pose_from_joint_rotations(dims, q, Eigen::Vector3f(0, 0, 0.93f), f);
  std::vector<CapsuleInstance> caps;
  append_avatar(f, dims, AvatarStyle{}, caps);
  const auto& arm = caps[index(Segment::upper_arm_l)];
  const Eigen::Vector3f along = b_of(arm) - a_of(arm);
  EXPECT_NEAR(along.z(), 0.0f, 1e-3f);
  EXPECT_NEAR(along.x(), static_cast<float>(0.186 * 1.75), 1e-3f);
  // The forearm starts where the upper arm ends.
  EXPECT_LT((a_of(caps[index(Segment::forearm_l)]) - b_of(arm)).norm(), 1e-4f);
}

TEST(AvatarGeometry, StyleAddsJointsAndAxes) {
  const BodyDimensions dims = body_dimensions_from_height(1.6);
  const PoseFrame f = reference_pose(dims, Eigen::Vector3f::Zero());
  std::vector<CapsuleInstance> solid, stick, axes;
  append_avatar(f, dims, AvatarStyle{}, solid);
  append_avatar(f, dims, AvatarStyle{true, false}, stick);
  append_avatar(f, dims, AvatarStyle{false, true}, axes);
  EXPECT_EQ(stick.size(), solid.size() + kSegmentCount);
  EXPECT_EQ(axes.size(), solid.size() + 3 * kSegmentCount);
  EXPECT_LT(stick[index(Segment::torso) * 2].radius_m,
            0.5f * solid[index(Segment::torso)].radius_m);
}

TEST(AvatarGeometry, FlagsTintAndLabelSegments) {
  const BodyDimensions dims = body_dimensions_from_height(1.75);
  PoseFrame f = reference_pose(dims, Eigen::Vector3f::Zero());
  const int knee = index(Segment::shank_l);
  f.segment_flags[knee] = kSegTracked | kSegLimitViolated;
  f.joint_violation_deg[knee] = 12.4f;
  f.segment_flags[index(Segment::head)] = kSegStale;
  f.segment_flags[index(Segment::hand_r)] = kSegMagDisturbed;
  std::vector<CapsuleInstance> caps;
  append_avatar(f, dims, AvatarStyle{}, caps);
  auto rgb = [&](int s) {
    return std::array<float, 3>{caps[s].rgba[0], caps[s].rgba[1], caps[s].rgba[2]};
  };
  EXPECT_EQ(rgb(knee), kRgbLimitViolated);
  EXPECT_EQ(rgb(index(Segment::head)), kRgbStale);
  EXPECT_EQ(rgb(index(Segment::hand_r)), kRgbMagDisturbed);
  EXPECT_NE(rgb(index(Segment::shank_r)), kRgbLimitViolated);
  // Left and right limbs differ so the user can tell them apart.
  EXPECT_NE(rgb(index(Segment::thigh_l)), rgb(index(Segment::thigh_r)));

  std::array<char, 32> label{};
  segment_label(f, knee, label);
  EXPECT_STREQ(label.data(), "LIMIT 12 DEG");
  segment_label(f, index(Segment::head), label);
  EXPECT_STREQ(label.data(), "STALE");
  segment_label(f, index(Segment::torso), label);
  EXPECT_STREQ(label.data(), "");
}

TEST(AvatarGeometry, NonFinitePoseDrawsNothing) {
  const BodyDimensions dims = body_dimensions_from_height(1.75);
  PoseFrame f = reference_pose(dims, Eigen::Vector3f::Zero());
  f.p_earth_segment_m[5][1] = std::numeric_limits<float>::quiet_NaN();
  std::vector<CapsuleInstance> caps;
  append_avatar(f, dims, AvatarStyle{}, caps);
  EXPECT_TRUE(caps.empty());
  PoseFrame zero;  // all-zero quaternions are not orientations either
  EXPECT_FALSE(pose_is_finite(zero));
}

TEST(AvatarGeometry, EarthAxesPointEastNorthUp) {
  std::vector<CapsuleInstance> caps;
  append_earth_axes(0.5f, caps);
  ASSERT_EQ(caps.size(), 3u);
  EXPECT_FLOAT_EQ(caps[0].b_m[0], 0.5f);
  EXPECT_FLOAT_EQ(caps[1].b_m[1], 0.5f);
  EXPECT_FLOAT_EQ(caps[2].b_m[2], 0.5f);
  EXPECT_GT(caps[0].rgba[0], caps[0].rgba[1]);  // x red
}

}  // namespace
}  // namespace mocap::viewer
