// Axis remap parsing and application (vectors and orientation).
#include <gtest/gtest.h>

#include "mocap/drivers/axis_remap.hpp"

using namespace mocap;

TEST(AxisRemap, IdentityAndPermutation) {
  EXPECT_TRUE(AxisRemap::parse("x,y,z").identity());
  const auto r = AxisRemap::parse("-y,x,z");
  const Eigen::Vector3d v = r.apply(Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(v, Eigen::Vector3d(-2, 1, 3));
}

TEST(AxisRemap, OrientationConsistentWithVectors) {
  const auto r = AxisRemap::parse("-y,x,z");
  const Eigen::Quaterniond q_ref_device(
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()));
  const Eigen::Vector3d v_device(0.3, -1.2, 2.0);
  // The same physical vector, expressed in the reference frame, must not change.
  const Eigen::Vector3d a = q_ref_device * v_device;
  const Eigen::Vector3d b = r.apply(q_ref_device) * r.apply(v_device);
  EXPECT_NEAR((a - b).norm(), 0, 1e-12);
}

TEST(AxisRemap, RejectsBadText) {
  EXPECT_THROW(AxisRemap::parse("x,x,z"), std::invalid_argument);
  EXPECT_THROW(AxisRemap::parse("x,y"), std::invalid_argument);
  EXPECT_THROW(AxisRemap::parse("-x,y,z"), std::invalid_argument);  // reflection
  EXPECT_THROW(AxisRemap::parse("a,b,c"), std::invalid_argument);
}
