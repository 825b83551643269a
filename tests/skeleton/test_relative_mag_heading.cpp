// Relative magnetometer heading smoothing (relative_mag_heading.hpp) with synthetic filter
// outputs: a sensor's true orientation, turned by its filter's magnetometer correction delta
// (q = Rz(delta) q_true when delta is the error). A short wobble of one sensor's correction
// relative to the pelvis sensor's is taken out of its heading, a lasting one is followed over
// tau_s, after a turn about the vertical over turn_tau_s (unless both gyro scales are
// calibrated); the pelvis and a common correction of every sensor pass unchanged.
#include <gtest/gtest.h>

#include <cmath>

#include "mocap/skeleton/quat_math.hpp"
#include "mocap/skeleton/relative_mag_heading.hpp"
#include "mocap/skeleton/rig.hpp"
#include "mocap/skeleton/skeleton.hpp"
#include "skeleton_test_util.hpp"

namespace mocap {
namespace relative_mag_heading_test {  // named: the test target is a unity build

using test::kMs;

constexpr int kPelvis = index(Segment::pelvis), kHand = index(Segment::hand_l);
constexpr double kDt = 0.01;  // 100 Hz

double heading_error_deg(const Eigen::Quaterniond& q, const Eigen::Quaterniond& truth) {
  const Eigen::Vector3d x = (q * truth.conjugate()) * Eigen::Vector3d::UnitX();
  return std::atan2(x.y(), x.x()) / kDegToRad;
}

RelativeMagHeading make(bool enabled = true) {
  RelativeMagHeadingOptions o;
  o.enabled = enabled;
  return RelativeMagHeading(RigMapping::full(), o);
}

/// Runs `seconds` of samples: the hand's true orientation raises the arm about y (no turn) or,
/// with turn_rad_s, turns about the vertical; delta_hand(t), delta_pelvis(t) are the filters'
/// magnetometer errors. Returns the hand's output heading error at the end, degrees; `worst`
/// gets the largest one.
template <class FH, class FP>
double run(RelativeMagHeading& r, double t0, double seconds, FH delta_hand, FP delta_pelvis,
           double turn_rad_s = 0, double* worst = nullptr) {
  double err = 0;
  for (double t = t0; t < t0 + seconds - 1e-9; t += kDt) {
    const int64_t t_ns = static_cast<int64_t>(std::llround(t * 1e9));
    const Eigen::Quaterniond pelvis_true = yaw_rotation(turn_rad_s * t);
    const Eigen::Quaterniond hand_true = pelvis_true * axis_rotation(1, 0.8 * std::sin(t));
    const double dp = delta_pelvis(t), dh = delta_hand(t);
    const Eigen::Quaterniond qp = r.apply(kPelvis, yaw_rotation(dp) * pelvis_true, t_ns, dp);
    EXPECT_NEAR(heading_error_deg(qp, pelvis_true), dp / kDegToRad, 1e-9);  // unchanged
    const Eigen::Quaterniond qh = r.apply(kHand, yaw_rotation(dh) * hand_true, t_ns, dh);
    // The joint's heading error: the hand's relative to the pelvis's.
    err = heading_error_deg(qh, hand_true) - dp / kDegToRad;
    if (worst) *worst = std::max(*worst, std::abs(err));
  }
  return err;
}

TEST(RelativeMagHeading, ShortWobbleOfOneSensorIsTakenOut) {
  // The hand's magnetometer heading wobbles by +-3 deg over 4 s (a hard-iron residual as the
  // arm moves); the pelvis's drifts slowly, which every segment must keep.
  const auto wobble = [](double t) { return 3 * kDegToRad * std::sin(2 * M_PI * t / 4); };
  const auto pelvis = [](double t) { return 0.05 * kDegToRad * t; };
  RelativeMagHeading off = make(false), on = make(true);
  double worst_off = 0, worst_on = 0;
  run(
      off, 0, 12, [&](double t) { return wobble(t) + pelvis(t); }, pelvis, 0, &worst_off);
  run(
      on, 0, 12, [&](double t) { return wobble(t) + pelvis(t); }, pelvis, 0, &worst_on);
  EXPECT_GT(worst_off, 2.9);
  EXPECT_LT(worst_on, 0.7);
}

TEST(RelativeMagHeading, CommonCorrectionPassesUnchanged) {
  RelativeMagHeading r = make();
  const auto common = [](double t) { return 5 * kDegToRad * std::sin(t); };
  double worst = 0;
  run(r, 0, 10, common, common, 0, &worst);
  EXPECT_LT(worst, 1e-9);
  EXPECT_NEAR(r.correction_rad(kHand), 0, 1e-12);
}

TEST(RelativeMagHeading, LastingDifferenceIsFollowedOverTau) {
  // The hand's magnetometer heading changes by 4 deg for good at t = 1 s: whether it was the
  // gyro or the field that was wrong, in the long term the magnetometer wins.
  RelativeMagHeading r = make();
  const auto zero = [](double) { return 0.0; };
  const auto step = [](double t) { return t >= 1 ? 4 * kDegToRad : 0.0; };
  run(r, 0, 1, step, zero);
  const double just_after = run(r, 1, 0.05, step, zero);
  EXPECT_NEAR(just_after, 0, 0.05);  // held: the output still has the old relative heading
  const double tau = r.options().tau_s;
  const double after_tau = run(r, 1.05, tau - 0.05, step, zero);
  EXPECT_NEAR(after_tau, 4 * (1 - std::exp(-1.0)), 0.2);
  const double after_5tau = run(r, tau + 1, 4 * tau, step, zero);
  EXPECT_NEAR(after_5tau, 4, 0.05);
}

TEST(RelativeMagHeading, AfterATurnTheMagnetometersAreFollowedFast) {
  // Turning at 60 deg/s, the gyros' scale errors turn the headings apart: the filters' relative
  // correction is followed over turn_tau_s, not tau_s.
  const auto zero = [](double) { return 0.0; };
  const auto step = [](double t) { return t >= 1 ? 4 * kDegToRad : 0.0; };
  RelativeMagHeading still = make(), turning = make();
  const double w = 60 * kDegToRad;
  run(still, 0, 4, step, zero);
  run(turning, 0, 4, step, zero, w);
  const double e_still = run(still, 4, 0.01, step, zero);
  const double e_turning = run(turning, 4, 0.01, step, zero, w);
  EXPECT_LT(e_still, 4 * (1 - std::exp(-3.0 / 20)) + 0.05);  // 3 s of tau_s = 20 s: 0.56
  EXPECT_GT(e_turning, 3.0);
}

TEST(RelativeMagHeading, CalibratedGyroScalesKeepTauAfterATurn) {
  // With both sensors' gyro scales calibrated a turn does not turn their headings apart: the
  // relative correction keeps tau_s. One calibrated sensor is not enough.
  const auto zero = [](double) { return 0.0; };
  const auto step = [](double t) { return t >= 1 ? 4 * kDegToRad : 0.0; };
  const double w = 60 * kDegToRad;
  RelativeMagHeadingOptions o;
  o.enabled = true;
  o.gyro_scale_calibrated[kHand] = o.gyro_scale_calibrated[kPelvis] = true;
  RelativeMagHeading both(RigMapping::full(), o);
  o.gyro_scale_calibrated[kPelvis] = false;
  RelativeMagHeading hand_only(RigMapping::full(), o);
  run(both, 0, 4, step, zero, w);
  run(hand_only, 0, 4, step, zero, w);
  EXPECT_LT(run(both, 4, 0.01, step, zero, w), 4 * (1 - std::exp(-3.0 / 20)) + 0.05);
  EXPECT_GT(run(hand_only, 4, 0.01, step, zero, w), 3.0);
}

TEST(RelativeMagHeading, UnknownCorrectionRestarts) {
  // A NaN (no magnetometer heading, or not converged) passes the sample and restarts the
  // segment; for the reference, every segment.
  RelativeMagHeading r = make();
  const auto zero = [](double) { return 0.0; };
  const auto step = [](double t) { return t >= 1 ? 4 * kDegToRad : 0.0; };
  run(r, 0, 2, step, zero);
  const Eigen::Quaterniond q = yaw_rotation(0.3);
  EXPECT_EQ(r.apply(kHand, q, 2'000 * kMs, std::nan("")).coeffs(), q.coeffs());
  EXPECT_NEAR(run(r, 2.01, 0.1, step, zero), 4, 1e-3);
  run(
      r, 2.11, 1, [](double) { return 0.0; }, zero);  // smoothing again: the hand held at 4
  EXPECT_GT(std::abs(r.correction_rad(kHand)), 3 * kDegToRad);
  r.apply(kPelvis, q, 3'200 * kMs, std::nan(""));
  EXPECT_EQ(r.apply(kHand, q, 3'200 * kMs, 0.1).coeffs(), q.coeffs());  // no reference
  EXPECT_NEAR(run(r, 3.21, 0.1, zero, zero), 0, 1e-3);  // restarted from its own heading
}

TEST(RelativeMagHeading, ResetStartsFromTheSensorsOwnHeadings) {
  RelativeMagHeading r = make();
  const auto zero = [](double) { return 0.0; };
  const auto step = [](double t) { return t >= 1 ? 4 * kDegToRad : 0.0; };
  run(r, 0, 2, step, zero);
  EXPECT_GT(std::abs(r.correction_rad(kHand)), 3 * kDegToRad);
  r.reset();
  EXPECT_NEAR(run(r, 2, 0.1, step, zero), 4, 1e-3);  // the new start: the filter's own heading
}

TEST(RelativeMagHeading, SkeletonCalibrationRestartsTheSmoothing) {
  SkeletonOptions o;
  o.relative_mag_heading.enabled = true;
  Skeleton sk(BodyModel{}, default_joint_limits(), RigMapping::full(), o);
  Calibration identity;  // sensors aligned with their segments
  identity.valid = true;
  identity.calibrated.fill(true);
  const double d = 4 * kDegToRad;
  // Not calibrated yet: no smoothing (the filters' start-up headings are no joint's).
  sk.set_sensor_orientation(kPelvis, Eigen::Quaterniond::Identity(), 0, 0, 0.0);
  sk.set_sensor_orientation(kHand, Eigen::Quaterniond::Identity(), 0, 0, 0.0);
  sk.set_sensor_orientation(kPelvis, Eigen::Quaterniond::Identity(), 10 * kMs, 0, 0.0);
  sk.set_sensor_orientation(kHand, yaw_rotation(d), 10 * kMs, 0, d);
  EXPECT_EQ(sk.relative_mag_heading().correction_rad(kHand), 0.0);
  sk.set_calibration(identity);
  for (int k = 0; k < 100; ++k) {
    const int64_t t = (k + 2) * 10 * kMs;
    sk.set_sensor_orientation(kPelvis, Eigen::Quaterniond::Identity(), t, 0, 0.0);
    // The hand's correction jumps by 4 deg at 0.5 s: held by the smoothing.
    const double dh = k >= 50 ? d : 0.0;
    sk.set_sensor_orientation(kHand, yaw_rotation(dh), t, 0, dh);
  }
  PoseFrame f;
  sk.solve(f);
  EXPECT_LT(
      std::abs(heading_error_deg(sk.q_earth_segment()[kHand], Eigen::Quaterniond::Identity())),
      4 * (1 - std::exp(-0.5 / 20)) + 0.01);
  sk.set_calibration(identity);
  sk.set_sensor_orientation(kPelvis, Eigen::Quaterniond::Identity(), 1000 * kMs, 0, 0.0);
  sk.set_sensor_orientation(kHand, yaw_rotation(d), 1000 * kMs, 0, d);
  sk.solve(f);
  EXPECT_NEAR(heading_error_deg(sk.q_earth_segment()[kHand], Eigen::Quaterniond::Identity()), 4,
              1e-6);
}

}  // namespace relative_mag_heading_test
}  // namespace mocap
