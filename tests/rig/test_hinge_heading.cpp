// A knee's relative heading held to its hinge (rig/hinge_heading.hpp): the lower segment's
// axis, seen in a frame that drifts against the upper's, is turned back onto the upper's axis
// within the correction's time constant, handed over at 10 Hz; an error no drift can make is
// refused and counted; a vertical axis says nothing about heading.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "mocap/core/units.hpp"
#include "mocap/rig/hinge_heading.hpp"

namespace mocap::rig {
namespace {

Eigen::Vector3d turned_by_yaw(const Eigen::Vector3d& v, double yaw_rad) {
  return Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) * v;
}

/// Runs the hold at 100 Hz for `seconds`: the body turns, the hinge's axis tilts a little, the
/// lower frame is off by offset0_rad and drifts at drift_rad_s; the correction is applied
/// whenever the hold says it is due (10 Hz). Returns the lower frame's error left at the end, rad.
double run(HingeHeading& hold, double seconds, double offset0_rad, double drift_rad_s) {
  constexpr double dt = 0.01;
  double applied_rad = 0;
  double error_rad = offset0_rad;
  for (int n = 1; n <= static_cast<int>(seconds / dt); ++n) {
    const double t = n * dt;
    const Eigen::Vector3d axis =
        turned_by_yaw(Eigen::Vector3d(0, std::cos(0.2 * std::sin(t)), 0.2 * std::sin(t)),
                      0.8 * std::sin(0.1 * t));
    error_rad = offset0_rad + drift_rad_s * t - applied_rad;
    hold.add(axis, turned_by_yaw(axis, error_rad), dt);
    if (hold.due(static_cast<int64_t>(n) * 10'000'000)) applied_rad -= hold.take();
  }
  return error_rad;
}

TEST(HingeHeading, TurnsAnOffsetBackAndFollowsADrift) {
  HingeHeadingOptions o;
  o.tau_s = 2.0;
  // A 20 deg offset: after five time constants under 2 % of it is left (e^-5 is 0.7 %; the
  // axis' tilt weighs a little less than one).
  HingeHeading a(o);
  EXPECT_LT(std::abs(run(a, 5 * o.tau_s, 20 * kRadPerDeg, 0)), 0.02 * 20 * kRadPerDeg);
  // A drift of 1 deg/s is followed with the lag of a first-order loop (rate x tau = 2 deg),
  // not left to grow (60 deg in the minute).
  HingeHeading b(o);
  const double lag_rad = run(b, 60, 0, 1 * kRadPerDeg);
  EXPECT_GT(lag_rad, 1.5 * kRadPerDeg);
  EXPECT_LT(lag_rad, 2.5 * kRadPerDeg);
  EXPECT_EQ(b.take_refused(), 0);
}

TEST(PendingYaw, HandsOverAtTenHertzAndStartsOverOnReset) {
  PendingYaw p;
  int handed = 0;
  double taken_rad = 0;
  for (int64_t t_ns = 10'000'000; t_ns <= 1'000'000'000; t_ns += 10'000'000) {  // 1 s at 100 Hz
    p.add(0.01);
    if (p.due(t_ns)) {
      ++handed;
      taken_rad += p.take();
    }
  }
  EXPECT_EQ(handed, 10);
  EXPECT_NEAR(taken_rad + p.take(), 1.0, 1e-12);  // nothing lost between hand-overs
  EXPECT_EQ(p.take(), 0.0);
  p.add(0.5);
  EXPECT_FALSE(p.due(1'010'000'000));  // 10 ms after the last hand-over
  p.reset();  // a new calibration: nothing pending, a hand-over due at once
  EXPECT_EQ(p.take(), 0.0);
  EXPECT_TRUE(p.due(1'010'000'000));
}

TEST(HingeHeading, RefusesAnErrorNoDriftMakes) {
  HingeHeading hold;
  for (int n = 0; n < 100; ++n)
    hold.add(Eigen::Vector3d::UnitY(), turned_by_yaw(Eigen::Vector3d::UnitY(), 90 * kRadPerDeg),
             0.01);
  EXPECT_EQ(hold.take(), 0.0);
  EXPECT_EQ(hold.take_refused(), 100);
  EXPECT_EQ(hold.take_refused(), 0);
}

// A lost heading being found: the same 90 deg is followed (at the time constant), and the time
// followed is counted.
TEST(HingeHeading, FollowsAnyErrorWhileALostHeadingIsFound) {
  HingeHeadingOptions o;
  o.start_s = 0;  // the steady time constant from the start (the start's own test below)
  HingeHeading hold(o);
  double taken_rad = 0;
  for (int n = 0; n < 100; ++n) {
    hold.add(Eigen::Vector3d::UnitY(), turned_by_yaw(Eigen::Vector3d::UnitY(), 90 * kRadPerDeg),
             0.01, /*refuse_far=*/false);
    if (hold.due(n * 10'000'000)) taken_rad += hold.take();
  }
  taken_rad += hold.take();
  EXPECT_EQ(hold.take_refused(), 0);
  // 1 s at a 2 s time constant, the error held: half of it.
  EXPECT_NEAR(taken_rad, -0.5 * 90 * kRadPerDeg, 1e-9);  // the lower axis back onto the upper
  EXPECT_NEAR(hold.followed_s(), 1.0, 1e-9);
  hold.reset();
  EXPECT_EQ(hold.followed_s(), 0.0);
}

TEST(HingeHeading, TakesOutTheCalibrationsErrorFasterAtTheStart) {
  // A 10 deg error held: taken at the start's 0.5 s time constant for the first 2 s followed
  // (twice the error per second), then at 2 s (half of it per second).
  HingeHeading hold;
  const double error_rad = 10 * kRadPerDeg;
  const auto follow = [&](double seconds) {
    double taken_rad = 0;
    for (int n = 0; n < static_cast<int>(std::lround(seconds * 100)); ++n) {
      hold.add(Eigen::Vector3d::UnitY(), turned_by_yaw(Eigen::Vector3d::UnitY(), error_rad), 0.01);
      taken_rad += hold.take();
    }
    return taken_rad;
  };
  EXPECT_NEAR(follow(2.0), -2 * 2 * error_rad, 1e-9);
  EXPECT_NEAR(follow(1.0), -0.5 * error_rad, 1e-9);
  hold.reset();  // starts over: fast again
  EXPECT_NEAR(follow(1.0), -2 * error_rad, 1e-9);
}

TEST(HingeHeading, AVerticalAxisSaysNothing) {
  HingeHeading hold;
  const Eigen::Vector3d up(0.001, 0, 1);
  for (int n = 0; n < 100; ++n)
    hold.add(up.normalized(), turned_by_yaw(up, 30 * kRadPerDeg).normalized(), 0.01);
  EXPECT_EQ(hold.take(), 0.0);
}

}  // namespace
}  // namespace mocap::rig
