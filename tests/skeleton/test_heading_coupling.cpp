// Heading coupling at the hinges (heading_coupling.hpp) with synthetic truth: a thigh and shank
// (knee, flexion about y) whose sensors' earth frames differ by a known heading offset. The
// offset is recovered while the knee flexes, nothing changes while it is straight, a wrong
// constraint is capped, and a sensor flagged disturbed is the one that gets turned.
#include <gtest/gtest.h>

#include <cmath>

#include "mocap/skeleton/heading_coupling.hpp"
#include "mocap/skeleton/hinge_calibration.hpp"
#include "mocap/skeleton/quat_math.hpp"
#include "mocap/skeleton/skeleton.hpp"
#include "skeleton_test_util.hpp"

namespace mocap {
namespace heading_coupling_test {  // named: the test target is a unity build

using test::kMs;

constexpr int kThigh = index(Segment::thigh_r), kShank = index(Segment::shank_r),
              kFoot = index(Segment::foot_r);

struct Leg {
  Eigen::Quaterniond thigh, shank;
};

/// True thigh and shank orientations at t: the body turns slowly, the hip swings, the knee flexes
/// by knee_max_rad * (1 - cos) / 2 (0 = straight leg), or is held at -knee_max_rad when that is
/// negative; abduct_rad turns the shank about its own x axis (not a hinge motion).
Leg true_leg(double t, double knee_max_rad, double abduct_rad = 0) {
  const Eigen::Quaterniond body = yaw_rotation(0.3 * t);
  const Eigen::Quaterniond thigh = body * axis_rotation(1, -0.4 * std::sin(2.0 * t));
  const double knee =
      knee_max_rad < 0 ? -knee_max_rad : knee_max_rad * 0.5 * (1 - std::cos(3.0 * t));
  return {thigh, thigh * axis_rotation(1, knee) * axis_rotation(0, abduct_rad)};
}

struct CouplingRun {
  HeadingCoupling coupling;
  double joint_error_deg = 0;  // corrected knee rotation vs truth at the end
};

/// Feeds `seconds` at 100 Hz: the shank's sensor earth frame is turned by offset_deg.
CouplingRun run(double offset_deg, double knee_max_rad, double seconds,
                bool thigh_disturbed = false, HeadingCouplingOptions o = {.enabled = true},
                double abduct_rad = 0) {
  CouplingRun r{HeadingCoupling(RigMapping::full(), o)};
  std::array<Eigen::Quaterniond, kSegmentCount> q;
  q.fill(Eigen::Quaterniond::Identity());
  std::array<bool, kSegmentCount> have{}, disturbed{};
  have[kThigh] = have[kShank] = have[kFoot] = true;
  disturbed[kThigh] = thigh_disturbed;
  const Eigen::Quaterniond off = yaw_rotation(offset_deg * kDegToRad);
  Leg leg{};
  for (int k = 0; k <= static_cast<int>(seconds * 100); ++k) {
    leg = true_leg(k * 0.01, knee_max_rad, abduct_rad);
    q[kThigh] = leg.thigh;
    q[kShank] = off * leg.shank;
    q[kFoot] = q[kShank];
    r.coupling.update(q, have, disturbed, static_cast<int64_t>(k) * 10 * kMs);
  }
  const Eigen::Quaterniond est =
      r.coupling.apply(kThigh, q[kThigh]).conjugate() * r.coupling.apply(kShank, q[kShank]);
  r.joint_error_deg = angle_between_deg(est, leg.thigh.conjugate() * leg.shank);
  return r;
}

TEST(HeadingCoupling, RecoversAHeadingOffsetWhileTheKneeFlexes) {
  const CouplingRun r = run(8.0, 1.5, 30.0);
  const CouplingHinge& h = r.coupling.hinges()[1];  // thigh_r - shank_r
  EXPECT_NEAR(h.offset_deg, 8.0, 0.2);
  EXPECT_GT(h.observed_s, 5.0);
  // Both clean: the thigh is the reference, the shank is turned onto it.
  const auto& c = r.coupling.correction_rad();
  EXPECT_EQ(c[kThigh], 0.0);
  EXPECT_NEAR(c[kShank] * kRadToDeg, -8.0, 0.2);
  EXPECT_NEAR(c[kFoot], c[kShank], 1e-15);  // carried to the foot: the ankle keeps its reading
  EXPECT_LT(r.joint_error_deg, 0.3);
  // Without the coupling the knee reads the offset as a twist.
  const CouplingRun off = run(8.0, 1.5, 30.0, false, HeadingCouplingOptions{.enabled = false});
  EXPECT_GT(off.joint_error_deg, 5.0);
}

TEST(HeadingCoupling, StraightJointChangesNothing) {
  // Knee straight: a heading offset and a mounting twist look the same; no correction.
  const CouplingRun r = run(8.0, 0.0, 30.0);
  for (double c : r.coupling.correction_rad())
    EXPECT_EQ(c, 0.0);
  EXPECT_EQ(r.coupling.hinges()[1].observed_s, 0.0);
}

TEST(HeadingCoupling, NonHingeMotionIsNotReadAsHeading) {
  // The knee held at 46 deg and the shank turned 29 deg about its own x axis (not a hinge): the
  // two flexion axes' elevations differ and no sample is used.
  const CouplingRun r = run(8.0, -0.8, 30.0, false, HeadingCouplingOptions{.enabled = true}, 0.5);
  EXPECT_EQ(r.coupling.hinges()[1].observed_s, 0.0);
  EXPECT_EQ(r.coupling.correction_rad()[kShank], 0.0);
  // The same held knee without the abduction is a hinge: observed and corrected.
  const CouplingRun hinge = run(8.0, -0.8, 30.0);
  EXPECT_NEAR(hinge.coupling.hinges()[1].offset_deg, 8.0, 0.2);
}

TEST(HeadingCoupling, RunawayIsCapped) {
  // A sensor turned by 60 deg on its segment: the constraint says 60, the cap holds 25.
  HeadingCouplingOptions o{.enabled = true};
  const CouplingRun r = run(60.0, 1.5, 120.0, false, o);
  EXPECT_NEAR(r.coupling.hinges()[1].offset_deg, o.max_correction_deg, 1e-9);
  for (double c : r.coupling.correction_rad())
    EXPECT_LE(std::abs(c) * kRadToDeg, o.max_correction_deg + 1e-9);
}

TEST(HeadingCoupling, DisturbedSensorIsTheOneTurned) {
  // The thigh's magnetometer is flagged, the shank's is not: the thigh is turned onto the
  // shank's heading instead.
  const CouplingRun r = run(8.0, 1.5, 30.0, true);
  const auto& c = r.coupling.correction_rad();
  EXPECT_NEAR(c[kThigh] * kRadToDeg, 8.0, 0.2);
  EXPECT_NEAR(c[kShank] * kRadToDeg, 0.0, 0.05);
  EXPECT_LT(r.joint_error_deg, 0.3);
}

TEST(HeadingCoupling, SkeletonAppliesItToTheKnee) {
  SkeletonOptions so;
  so.heading_coupling.enabled = true;
  Skeleton sk(BodyModel(BodyModelConfig{}), default_joint_limits(), RigMapping::full(), so);
  Calibration cal;
  cal.valid = true;
  cal.calibrated.fill(true);
  sk.set_calibration(cal);
  const Eigen::Quaterniond off = yaw_rotation(6.0 * kDegToRad);
  PoseFrame f;
  Leg leg{};
  for (int k = 0; k <= 3000; ++k) {
    leg = true_leg(k * 0.01, 1.5);
    const int64_t t = static_cast<int64_t>(k) * 10 * kMs;
    for (int s = 0; s < kSegmentCount; ++s)
      sk.set_sensor_orientation(s, Eigen::Quaterniond::Identity(), t);
    sk.set_sensor_orientation(kThigh, leg.thigh, t);
    sk.set_sensor_orientation(kShank, off * leg.shank, t);
    sk.solve(f);
  }
  EXPECT_NEAR(sk.heading_coupling().hinges()[1].offset_deg, 6.0, 0.2);
  EXPECT_LT(angle_between_deg(sk.q_parent_segment()[kShank], leg.thigh.conjugate() * leg.shank),
            0.3);
  // A heading reset aligns every segment's heading: the coupling starts again from it.
  sk.reset_heading();
  EXPECT_EQ(sk.heading_coupling().hinges()[1].offset_deg, 0.0);
  EXPECT_EQ(sk.heading_coupling().correction_rad()[kShank], 0.0);
}

/// Feeds `seconds` of the flexing knee (shank sensor's earth frame turned by 8 deg) through
/// calibration `cal` into `c`, starting at sample k0.
void feed(HeadingCoupling& c, const Calibration& cal, int k0, double seconds) {
  std::array<Eigen::Quaterniond, kSegmentCount> q;
  q.fill(Eigen::Quaterniond::Identity());
  std::array<bool, kSegmentCount> have{}, disturbed{};
  have[kThigh] = have[kShank] = true;
  const Eigen::Quaterniond off = yaw_rotation(8.0 * kDegToRad);
  for (int k = k0; k <= k0 + static_cast<int>(seconds * 100); ++k) {
    const Leg leg = true_leg(k * 0.01, 1.5);
    q[kThigh] = cal.segment_from_sensor(kThigh, leg.thigh);
    q[kShank] = cal.segment_from_sensor(kShank, off * leg.shank);
    c.update(q, have, disturbed, static_cast<int64_t>(k) * 10 * kMs);
  }
}

TEST(HeadingCoupling, RebaseForgetsWhatAnEarlierMountingTaught) {
  // The true mountings are identity. For 4 s the shank's mounting is 10 deg off in yaw (the
  // N-pose's, before the refinement identified the knee); then the refinement corrects it.
  Calibration truth;
  truth.valid = true;
  truth.calibrated.fill(true);
  std::array<double, kSegmentCount> alpha{};
  alpha[kShank] = 10.0 * kDegToRad;
  const Calibration wrong = HingeAxisRefiner::apply(truth, alpha, 0.0);
  const HeadingCouplingOptions o{.enabled = true};
  // Reference: the true mounting from the start.
  HeadingCoupling ref(RigMapping::full(), o);
  feed(ref, truth, 0, 5.0);
  // Wrong mounting for 4 s, then rebased onto the truth and fed 1 s more.
  HeadingCoupling one(RigMapping::full(), o);
  feed(one, wrong, 0, 4.0);
  one.rebase(wrong, truth);
  feed(one, truth, 401, 0.99);
  EXPECT_NEAR(one.hinges()[1].offset_deg, ref.hinges()[1].offset_deg, 1e-6);
  EXPECT_NEAR(one.hinges()[1].observed_s, ref.hinges()[1].observed_s, 1e-9);
  // Without the history the offset keeps the wrong mounting's share.
  HeadingCouplingOptions no_hist = o;
  no_hist.history_samples = 0;
  HeadingCoupling stale(RigMapping::full(), no_hist);
  feed(stale, wrong, 0, 4.0);
  stale.rebase(wrong, truth);
  feed(stale, truth, 401, 0.99);
  EXPECT_GT(std::abs(stale.hinges()[1].offset_deg - ref.hinges()[1].offset_deg), 0.3);
}

TEST(HeadingCoupling, HistoryWindowDropsTheOldestIntoTheBaseState) {
  // A window shorter than the run: rebase with no calibration change reproduces the running
  // estimate exactly (the dropped frames were folded in, the kept ones replayed).
  HeadingCouplingOptions o{.enabled = true};
  o.history_samples = 300;
  Calibration cal;
  cal.valid = true;
  cal.calibrated.fill(true);
  HeadingCoupling c(RigMapping::full(), o);
  feed(c, cal, 0, 30.0);
  const double before = c.hinges()[1].offset_deg;
  EXPECT_NEAR(before, 8.0, 0.3);
  c.rebase(cal, cal);
  EXPECT_NEAR(c.hinges()[1].offset_deg, before, 1e-9);
}

}  // namespace heading_coupling_test
}  // namespace mocap
