// Orbit camera: projection geometry and interaction limits.
#include <gtest/gtest.h>

#include "mocap/viewer/camera.hpp"

namespace mocap::viewer {
namespace {

TEST(OrbitCamera, TargetProjectsToTheCentreAndAxesGoTheRightWay) {
  OrbitCamera c;
  c.target_m = {1, 2, 0.9f};
  c.yaw_deg = 0;  // eye on +x of the target, looking west
  c.pitch_deg = 0;
  const auto centre = c.project(c.target_m, 640, 480);
  ASSERT_TRUE(centre);
  EXPECT_NEAR(centre->x(), 320, 0.5);
  EXPECT_NEAR(centre->y(), 240, 0.5);
  // Looking west, north (+y) is on the right; up is up (smaller row).
  const auto north = c.project(c.target_m + Eigen::Vector3f(0, 0.5f, 0), 640, 480);
  const auto up = c.project(c.target_m + Eigen::Vector3f(0, 0, 0.5f), 640, 480);
  EXPECT_GT(north->x(), 330);
  EXPECT_LT(up->y(), 230);
  EXPECT_FALSE(c.project(c.eye_m() + Eigen::Vector3f(1, 0, 0), 640, 480)) << "behind the eye";
}

TEST(OrbitCamera, ZoomPanAndOrbitStayInRange) {
  OrbitCamera c;
  const float d = c.distance_m;
  c.zoom(1);
  EXPECT_LT(c.distance_m, d);
  for (int i = 0; i < 1000; ++i)
    c.zoom(5);
  EXPECT_GE(c.distance_m, 0.3f);
  for (int i = 0; i < 100; ++i)
    c.orbit(0, 1000);
  EXPECT_LE(c.pitch_deg, 85.0f);
  OrbitCamera p;
  const Eigen::Vector3f before = p.target_m;
  p.pan(-100, 0, 720);  // drag left: the scene follows the mouse to the left
  const auto moved = p.project(before, 1280, 720);
  EXPECT_LT(moved->x(), 640 - 50);
}

TEST(CrowdLayout, AvatarsStandApartAroundTheOrigin) {
  EXPECT_EQ(crowd_origin(0, 1), Eigen::Vector3f::Zero());
  Eigen::Vector3f sum = Eigen::Vector3f::Zero();
  for (int i = 0; i < 150; ++i) {
    sum += crowd_origin(i, 150);
    for (int j = 0; j < i; ++j)
      EXPECT_GE((crowd_origin(i, 150) - crowd_origin(j, 150)).norm(), 1.2f);
  }
  EXPECT_LT((sum / 150).norm(), 1.0f);
}

}  // namespace
}  // namespace mocap::viewer
