// Anthropometric body model: proportions of a standing person.
#include <gtest/gtest.h>

#include "mocap/skeleton/body_model.hpp"

namespace mocap {

TEST(BodyModel, StandingProportions) {
  const auto d = body_dimensions_from_height(1.80);
  const auto p = reference_joint_positions(d);
  const auto z = [&](Segment s) { return p[index(s)].z(); };
  // Ankle just above the floor, knees below hips, shoulders below the head.
  EXPECT_NEAR(z(Segment::foot_l), 0.039 * 1.80, 1e-9);
  EXPECT_LT(z(Segment::shank_l), z(Segment::thigh_l));
  EXPECT_LT(z(Segment::upper_arm_r), z(Segment::head));
  // Head top at the person's height.
  const double head_top = z(Segment::head) + d.end_offset_m[index(Segment::head)].z();
  EXPECT_NEAR(head_top, 1.80, 0.02);
  // Left is +y, symmetric with right.
  EXPECT_GT(p[index(Segment::hand_l)].y(), 0);
  EXPECT_NEAR(p[index(Segment::hand_l)].y(), -p[index(Segment::hand_r)].y(), 1e-12);
  // Scales linearly with height.
  const auto d2 = body_dimensions_from_height(0.90);
  EXPECT_NEAR(d2.joint_offset_m[index(Segment::shank_r)].norm() * 2,
              d.joint_offset_m[index(Segment::shank_r)].norm(), 1e-12);
}

}  // namespace mocap
