// HeadingFromMotion: the yaw between a segment's horizontal signal and its reference's.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include <Eigen/Geometry>

#include "mocap/rig/heading_from_motion.hpp"

namespace mocap::rig {
namespace {

constexpr double kDeg = std::numbers::pi / 180;
const int kShank = index(Segment::shank_r), kFoot = index(Segment::foot_r);

std::array<int, kSegmentCount> foot_follows_shank() {
  std::array<int, kSegmentCount> ref;
  ref.fill(-1);
  ref[kFoot] = kShank;
  return ref;
}

Eigen::Vector3d yawed(const Eigen::Vector3d& w, double yaw) {
  return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * w;
}

// The foot sensor's frame is 70 deg off; its rates are the shank's plus a joint rate of its own.
TEST(HeadingFromMotion, FindsTheYawBetweenCorrelatedRatesAndContinuesAfterItIsApplied) {
  HeadingFromMotion h;
  h.reset(foot_follows_shank());
  ASSERT_TRUE(h.active());
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0, 1);
  double offset = -70 * kDeg;  // foot frame = world turned by -70 deg
  double yaw = 0;
  EXPECT_FALSE(h.estimate(kFoot, yaw));  // no evidence yet
  bool found = false;
  for (int k = 0; k < 2000; ++k) {
    const int64_t t = static_cast<int64_t>(k) * 10'000'000;
    const Eigen::Vector3d shank(2 * std::sin(k * 0.05), 0.3 * n(rng), 0.2 * n(rng));
    const Eigen::Vector3d foot = shank + Eigen::Vector3d(0.5 * n(rng), 0.5 * n(rng), 0.3 * n(rng));
    h.add_reference(kFoot, shank, t);
    h.add(kFoot, yawed(foot, offset), t);
    if (k % 10 == 0 && h.estimate(kFoot, yaw)) {
      h.applied(kFoot, yaw);
      offset += yaw;  // the caller turns the foot's alignment
      found = true;
    }
  }
  ASSERT_TRUE(found);
  EXPECT_NEAR(offset, 0, 2 * kDeg);
  ASSERT_TRUE(h.estimate(kFoot, yaw));
  EXPECT_NEAR(yaw, 0, 2 * kDeg);
}

TEST(HeadingFromMotion, UncorrelatedRatesGiveNoYaw) {
  HeadingFromMotion h;
  h.reset(foot_follows_shank());
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0, 1);
  for (int k = 0; k < 2000; ++k) {
    const int64_t t = static_cast<int64_t>(k) * 10'000'000;
    h.add_reference(kFoot, Eigen::Vector3d(n(rng), n(rng), 0), t);
    h.add(kFoot, Eigen::Vector3d(n(rng), n(rng), 0), t);
  }
  double yaw = 0;
  EXPECT_FALSE(h.estimate(kFoot, yaw));
  // Segments without a reference never get one.
  EXPECT_FALSE(h.estimate(kShank, yaw));
}

// A jump: half a second of large signals at the opposite angle after seconds of ordinary motion
// at the right one. Each instant's weight saturates, so the burst cannot turn the estimate over.
TEST(HeadingFromMotion, ABurstOfLargeOppositeSignalsDoesNotOutvoteOrdinaryMotion) {
  HeadingFromMotion h;
  h.reset(foot_follows_shank());
  const Eigen::Vector3d v(1.0, 0.5, 0);
  int k = 0;
  for (; k < 500; ++k) {  // 5 s at 1 unit, same direction: yaw 0
    const int64_t t = static_cast<int64_t>(k) * 10'000'000;
    h.add_reference(kFoot, v * std::sin(k * 0.3), t);
    h.add(kFoot, v * std::sin(k * 0.3), t);
  }
  for (; k < 550; ++k) {  // 0.5 s at 30 units, opposite
    const int64_t t = static_cast<int64_t>(k) * 10'000'000;
    h.add_reference(kFoot, 30 * v * std::sin(k * 0.3), t);
    h.add(kFoot, -30 * v * std::sin(k * 0.3), t);
  }
  double yaw = 1;
  ASSERT_TRUE(h.estimate(kFoot, yaw));
  EXPECT_NEAR(yaw, 0, 1e-6);
  // Without saturation the burst wins (what the default guards against).
  HeadingFromMotionOptions o;
  o.saturation = 1e12;
  HeadingFromMotion raw(o);
  raw.reset(foot_follows_shank());
  for (k = 0; k < 550; ++k) {
    const int64_t t = static_cast<int64_t>(k) * 10'000'000;
    const double g = k < 500 ? 1 : 30;
    raw.add_reference(kFoot, g * v * std::sin(k * 0.3), t);
    raw.add(kFoot, (k < 500 ? g : -g) * v * std::sin(k * 0.3), t);
  }
  ASSERT_TRUE(raw.estimate(kFoot, yaw));
  EXPECT_NEAR(std::abs(yaw), std::numbers::pi, 1e-6);
}

TEST(HeadingFromMotion, StaleReferenceSamplesAreNotPaired) {
  HeadingFromMotion h;
  h.reset(foot_follows_shank());
  h.add_reference(kFoot, Eigen::Vector3d(3, 0, 0), 0);
  for (int k = 1; k < 1000; ++k)  // the shank went silent: nothing to pair with
    h.add(kFoot, Eigen::Vector3d(0, 3, 0), static_cast<int64_t>(k) * 10'000'000);
  double yaw = 0;
  EXPECT_FALSE(h.estimate(kFoot, yaw));
}

}  // namespace
}  // namespace mocap::rig
