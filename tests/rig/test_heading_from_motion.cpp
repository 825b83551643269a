// HeadingFromMotion: the yaw between a segment's horizontal signal and its reference's.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include <Eigen/Geometry>

#include "mocap/core/units.hpp"
#include "mocap/rig/heading_from_motion.hpp"

namespace mocap::rig {
namespace {

constexpr double kDeg = kRadPerDeg;
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

// The reference's alignment turns (a held pair's headings each follow half the drift): the
// evidence gathered so far is carried into its new frame, so the estimate moves by the turn
// at once and stays consistent with the samples that follow.
TEST(HeadingFromMotion, AReferenceTurnedCarriesTheEvidenceIntoItsNewFrame) {
  HeadingFromMotion h;
  h.reset(foot_follows_shank());
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0, 1);
  const double foot_offset = 20 * kDeg;
  double ref_offset = 0;
  int64_t t = 0;
  const auto feed = [&](int count) {
    for (int k = 0; k < count; ++k, t += 10'000'000) {
      const Eigen::Vector3d w(2 * std::sin(t * 5e-8), 0.5 * n(rng), 0.2 * n(rng));
      h.add_reference(kFoot, yawed(w, ref_offset), t);
      h.add(kFoot, yawed(w, foot_offset), t);
    }
  };
  feed(1000);
  double yaw = 0;
  ASSERT_TRUE(h.estimate(kFoot, yaw));
  EXPECT_NEAR(yaw, -20 * kDeg, 0.5 * kDeg);
  ref_offset = -10 * kDeg;
  h.reference_turned(kFoot, ref_offset);
  ASSERT_TRUE(h.estimate(kFoot, yaw));
  EXPECT_NEAR(yaw, -30 * kDeg, 0.5 * kDeg);  // at once, before any new sample
  feed(1000);
  ASSERT_TRUE(h.estimate(kFoot, yaw));
  EXPECT_NEAR(yaw, -30 * kDeg, 0.5 * kDeg);
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

// Sensors sample at their own instants: here the reference 5 ms after each segment sample. The
// signal's direction turns at 4 rad/s, so pairing a segment sample with the newest reference
// would read the yaw 1.1 deg off; paired with the segment's signal interpolated to the
// reference's time, the yaw is exact.
TEST(HeadingFromMotion, PairsEachReferenceSampleWithTheSegmentAtItsTime) {
  HeadingFromMotion h;
  h.reset(foot_follows_shank());
  const double offset = 30 * kDeg;
  const auto signal = [](double t_s) {
    return Eigen::Vector3d(2 * std::cos(4 * t_s), 2 * std::sin(4 * t_s), 0);
  };
  for (int k = 0; k < 1000; ++k) {
    const int64_t t = static_cast<int64_t>(k) * 10'000'000;
    h.add(kFoot, yawed(signal(t * 1e-9), -offset), t);
    h.add_reference(kFoot, signal((t + 5'000'000) * 1e-9), t + 5'000'000);
  }
  double yaw = 0;
  ASSERT_TRUE(h.estimate(kFoot, yaw));
  EXPECT_NEAR(yaw, offset, 0.02 * kDeg);
}

// A fit settles: while its evidence is young and agrees with itself it is settling (the caller
// may turn a found alignment faster); with enough evidence, or with evidence that disagrees,
// it is not.
TEST(HeadingFromMotion, SettlesOnceItHasEnoughCoherentEvidence) {
  HeadingFromMotionOptions o;
  HeadingFromMotion h(o);
  h.reset(foot_follows_shank());
  EXPECT_FALSE(h.settling(kShank));  // not fitted
  const Eigen::Vector3d v(1.0, 0.5, 0);
  int k = 0;
  const auto feed = [&](double seg_sign) {
    const int64_t t = static_cast<int64_t>(k) * 10'000'000;
    h.add_reference(kFoot, v * std::sin(k * 0.3), t);
    h.add(kFoot, seg_sign * v * std::sin(k * 0.3), t);
    ++k;
  };
  for (int i = 0; i < 20; ++i)
    feed(1);
  double yaw = 1;
  ASSERT_TRUE(h.estimate(kFoot, yaw));  // found from 0.2 s of motion
  EXPECT_TRUE(h.settling(kFoot));
  // Evidence that contradicts it: the resultant shrinks, the fit is not settling on anything.
  for (int i = 0; i < 20; ++i)
    feed(-1);
  EXPECT_FALSE(h.settling(kFoot));
  // Seconds of agreeing motion: settled.
  h.restart(kFoot, kShank);
  for (int i = 0; i < 1000; ++i)
    feed(1);
  EXPECT_FALSE(h.settling(kFoot));
  ASSERT_TRUE(h.estimate(kFoot, yaw));
  EXPECT_NEAR(yaw, 0, 1e-9);
}

}  // namespace
}  // namespace mocap::rig
