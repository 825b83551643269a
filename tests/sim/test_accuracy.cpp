// End-to-end accuracy regression: realistic consumer-MEMS sensors on the virtual performer,
// through our AttitudeFilter, N-pose calibration (refined from knee/elbow motion), the heading
// coupling at the hinges and the skeleton, against ground truth (seed 1, a second seed where a
// target is met; docs/accuracy.md has seeds 1..5). The 56 s sequence runs are in
// test_accuracy_sequence.cpp (label slow: minutes under the sanitizers).
// Where the targets (elbow/knee <= 2 deg, 3-DOF <= 3 deg, root drift <= 5 %) are met they
// are asserted; where they are NOT met (see docs/accuracy.md) the bound is a regression guard
// ~25 % above the measured value, named as such.
#include <gtest/gtest.h>

#include <array>

#include <cmath>

#include "accuracy_test_util.hpp"
#include "mocap/sim/accuracy.hpp"

namespace mocap::sim {
namespace {

TEST(Accuracy, WalkJointAnglesAndRootDrift) {
  // Targets met on every seed 1..5 for the joints (worst 1.68 / 2.30 deg); drift 2.2-5.2 %.
  for (uint64_t seed : {1, 3}) {
    AccuracyOptions o;
    o.motion = "walk";
    o.seed = seed;
    const AccuracyResult r = run_accuracy(o);
    ASSERT_TRUE(r.calibrated) << r.calibration_message;
    record(r);
    EXPECT_GT(r.distance_walked_m, 5.0);
    EXPECT_LE(r.root_drift_fraction, 0.05) << seed;  // target (measured 2.2 %, 2.7 %)
    // Targets, met: measured 1.27 / 1.39 deg (seed 1), 1.37 / 2.09 (seed 3).
    EXPECT_LE(r.hinge_max_rmse_deg, 2.0) << seed;
    EXPECT_LE(r.three_dof_max_rmse_deg, 3.0) << seed;
    // The knees identified their axes during the walk.
    EXPECT_GE(r.hinges_identified, 2);
  }
}

TEST(Accuracy, MountNormalsHeadingRemovesThePelvisClipsYawFromTheShoulders) {
  // The pelvis heading source turns every mounting by the belt clip's misalignment; the arm
  // raise's shoulders show it (seed 1, N-pose only: 3-DOF 5.50 deg). The mean over the mount
  // normals (the daemon's default): 4.07 (docs/accuracy.md). 3-DOF target still missed: guard.
  AccuracyOptions o;
  o.motion = "arm_raise";
  o.heading = HeadingSource::pelvis_sensor;
  const AccuracyResult pelvis = run_accuracy(o);
  o.heading = HeadingSource::mount_normals;
  const AccuracyResult normals = run_accuracy(o);
  ASSERT_TRUE(pelvis.calibrated && normals.calibrated) << normals.calibration_message;
  record(normals);
  EXPECT_LT(normals.three_dof_max_rmse_deg, pelvis.three_dof_max_rmse_deg - 1.0);
  EXPECT_LE(normals.three_dof_max_rmse_deg, 5.0);
}

TEST(Accuracy, HingeRefinementRemovesTheCalibrationHeadingError) {
  // Without refinement the pelvis sensor's mount misalignment turns every joint axis (2.36 deg
  // knee); the refinement identifies each segment's mounting yaw from the knees (1.28 deg).
  AccuracyOptions o;
  o.motion = "walk";
  o.heading = HeadingSource::pelvis_sensor;
  const AccuracyResult refined = run_accuracy(o);
  o.hinge_refine.enabled = false;
  const AccuracyResult npose_only = run_accuracy(o);
  ASSERT_TRUE(refined.calibrated && npose_only.calibrated);
  record(npose_only);
  EXPECT_LT(refined.hinge_max_rmse_deg, npose_only.hinge_max_rmse_deg - 0.5);
  // The identified segments' mounting yaw vs the true mount: the N-pose left ~4-5 deg.
  for (Segment s : {Segment::thigh_l, Segment::shank_l, Segment::thigh_r, Segment::shank_r}) {
    EXPECT_LT(std::abs(refined.mount_yaw_error_deg[index(s)]), 2.0) << name(s);
    EXPECT_GT(std::abs(npose_only.npose_mount_yaw_error_deg[index(s)]), 2.5) << name(s);
  }
}

TEST(Accuracy, SquatAfterCalibrationMoves) {
  // N-pose + calibration moves (knee bends with elbow curls), then the squat.
  for (uint64_t seed : {1, 2}) {
    AccuracyOptions o = after_moves("squat", seed);
    const AccuracyResult r = run_accuracy(o);
    ASSERT_TRUE(r.calibrated) << r.calibration_message;
    record(r);
    EXPECT_EQ(r.hinges_identified, 4);
    // Targets, met: measured 0.87 / 2.06 deg (seed 1), 0.70 / 2.07 (seed 2); seeds 1..5 at
    // most 1.92 / 3.002 (3-DOF missed by seed 4, docs/accuracy.md).
    EXPECT_LE(r.hinge_max_rmse_deg, 2.0) << seed;
    EXPECT_LE(r.three_dof_max_rmse_deg, 3.0) << seed;
  }
}

TEST(Accuracy, HingeResultsDoNotDependOnTheCalibrationHeadingSource) {
  // The refined calibration is the same with either heading source; the heading coupling's
  // offsets are re-estimated under it whenever it changes (HeadingCoupling::rebase), so the
  // knees and elbows are too. Before, the coupling kept what it learnt under the N-pose
  // calibration: squat after the moves, seed 4, 1.92 (pelvis) vs 2.16 deg (mount normals).
  AccuracyOptions o = after_moves("squat", 4);
  o.heading = HeadingSource::pelvis_sensor;
  const AccuracyResult pelvis = run_accuracy(o);
  o.heading = HeadingSource::mount_normals;
  const AccuracyResult normals = run_accuracy(o);
  ASSERT_TRUE(pelvis.calibrated && normals.calibrated) << normals.calibration_message;
  record(normals);
  EXPECT_NEAR(normals.hinge_max_rmse_deg, pelvis.hinge_max_rmse_deg, 0.02);
  EXPECT_LE(normals.hinge_max_rmse_deg, 2.0);  // target, met (measured 1.70 with either)
}

TEST(Accuracy, SquatWithMountNormalsHeading) {
  // N-pose only (no calibration moves), seed 5: with the pelvis belt clip as the heading the
  // squat misses both targets (4.86 / 4.77 deg); with the mount normals both are met: measured
  // 1.47 / 1.73.
  AccuracyOptions o;
  o.motion = "squat";
  o.seed = 5;
  o.heading = HeadingSource::mount_normals;
  const AccuracyResult r = run_accuracy(o);
  ASSERT_TRUE(r.calibrated) << r.calibration_message;
  record(r);
  EXPECT_LE(r.hinge_max_rmse_deg, 2.0);
  EXPECT_LE(r.three_dof_max_rmse_deg, 3.0);
}

TEST(Accuracy, BasinHysteresisMakesTheArmRaiseIndependentOfTheHeadingSource) {
  // Arm raise after the moves, seed 2: the right elbow's fit has two minima ~5 deg apart within
  // < 1 % of the cost, and the former search's pick depended on where its grid nodes fell: the
  // wrist's 3-DOF error was 2.97 deg with the pelvis heading, 4.07 with the mount normals. With
  // the hysteresis between basins (basin_margin 0.02, opt-in) both keep the basin in use:
  // measured 2.97 (pelvis) and 2.82 (normals).
  std::array<double, 2> three_dof{};
  for (int k = 0; k < 2; ++k) {
    AccuracyOptions o = after_moves("arm_raise", 2);
    o.hinge_refine.basin_margin = 0.02;
    o.heading = k ? HeadingSource::mount_normals : HeadingSource::pelvis_sensor;
    const AccuracyResult r = run_accuracy(o);
    ASSERT_TRUE(r.calibrated) << r.calibration_message;
    record(r);
    three_dof[k] = r.three_dof_max_rmse_deg;
    EXPECT_LE(r.three_dof_max_rmse_deg, 3.0) << k;
  }
  EXPECT_NEAR(three_dof[0], three_dof[1], 0.4);
}

TEST(Accuracy, TurnAfterCalibrationMovesKeepsTheKneeYaws) {
  // Seed 1: the knees' and elbows' yaw offsets found as the exact minimum of the hinge fit (not
  // the nearest node of a 0.05 deg grid window, which snapped to points degrees apart along the
  // cost's narrow valley): the turn after the moves went 2.51 -> 1.72 deg (now 1.55).
  // Seed 4: the calibration moves identify both knees' mounting yaws within 0.9 deg; the turn
  // on the spot that follows (60 deg/s about the vertical with steps) has rates inconsistent
  // with a rigid hinge by ~50x the moves' (hard-iron heading corrections, gyro scale errors,
  // rates of thigh and shank from instants apart), and unweighted its residuals moved the left
  // thigh and shank by 6 and 9 deg (mount yaw errors 5.3 / 8.0 deg, knee 3.03 deg). With each
  // block weighted by its own residual level: <= 0.63 deg, knee 2.58 deg; the rest is the two
  // filters' heading drifting apart by ~3 deg during the turn, which the heading coupling
  // follows with its 1 s time constant (3 s: 2.58; docs/accuracy.md): knee 1.94 deg.
  for (uint64_t seed : {1, 4}) {
    AccuracyOptions o = after_moves("turn", seed);
    const AccuracyResult r = run_accuracy(o);
    ASSERT_TRUE(r.calibrated) << r.calibration_message;
    record(r);
    EXPECT_EQ(r.hinges_identified, 4) << seed;
    for (Segment s : {Segment::thigh_l, Segment::shank_l, Segment::thigh_r, Segment::shank_r})
      EXPECT_LT(std::abs(r.mount_yaw_error_deg[index(s)]), 1.0) << name(s) << " seed " << seed;
    // Target, met: measured 1.55 (seed 1), 1.94 (seed 4, the left knee).
    EXPECT_LE(r.hinge_max_rmse_deg, 2.0) << seed;
  }
}

TEST(Accuracy, ArmRaiseThroughNinetyDegreesWithRealisticSensors) {
  AccuracyOptions o = after_moves("arm_raise");
  const AccuracyResult r = run_accuracy(o);
  ASSERT_TRUE(r.calibrated) << r.calibration_message;
  EXPECT_GT(r.frames, 1000);
  record(r);
  // Measured 1.23 / 2.12 deg (seed 1; 2.52 / 2.09 before the hinge fit's direction terms):
  // targets met (seeds 1..5: elbow up to 2.16, 3-DOF up to 3.28, docs/accuracy.md).
  EXPECT_LE(r.hinge_max_rmse_deg, 2.0);
  EXPECT_LE(r.three_dof_max_rmse_deg, 3.0);
  for (int s = 0; s < kSegmentCount; ++s)
    EXPECT_TRUE(std::isfinite(r.segment_rmse_deg[s]));
}

TEST(Accuracy, StillUpperArmPinsTheForearmsYaw) {
  // Ideal sensors and a perfect N-pose: every mounting yaw is right before the refinement. The
  // arm raise's elbow curls (upper arm still) leave the rate-norm fit a flat, fourth-order cost
  // in the forearm's yaw, and the rigid arm raises' small rate differences (filter tilt
  // corrections at different radii) moved it: left forearm 1.55 deg, elbow 1.67 deg. The
  // direction terms pin it to first order: measured 0.04 deg, elbow 0.34. (The fit's noise
  // weighting alone also keeps it, 0.19 deg: the raises' residuals are far above the curls', so
  // the former fit, rate norms unweighted, is the one that fails.)
  AccuracyOptions o = after_moves("arm_raise");
  o.sensor = SensorModelParams::ideal();
  const AccuracyResult r = run_accuracy(o);
  o.hinge_refine.direction_fraction = 0;
  o.hinge_refine.noise_weighting = false;
  const AccuracyResult norms_only = run_accuracy(o);
  ASSERT_TRUE(r.calibrated && norms_only.calibrated) << r.calibration_message;
  record(r);
  for (Segment s :
       {Segment::forearm_l, Segment::forearm_r, Segment::upper_arm_l, Segment::upper_arm_r})
    EXPECT_LT(std::abs(r.mount_yaw_error_deg[index(s)]), 0.3) << name(s);
  EXPECT_GT(std::abs(norms_only.mount_yaw_error_deg[index(Segment::forearm_l)]), 1.0);
  EXPECT_LE(r.hinge_max_rmse_deg, 0.6);
}

TEST(Accuracy, IdealSensorsIsolateThePipeline) {
  AccuracyOptions o;
  o.sensor = SensorModelParams::ideal();
  // The walk guards the accelerometer model: instantaneous accelerations sampled at 100 Hz
  // aliased foot-contact impulses into a bias that tilted the filters (7.6 / 10.3 deg here).
  for (const char* m : {"squat", "arm_raise", "walk"}) {
    o.motion = m;
    const AccuracyResult r = run_accuracy(o);
    ASSERT_TRUE(r.calibrated) << r.calibration_message;
    EXPECT_LE(r.hinge_max_rmse_deg, 2.0) << m;  // target (measured <= 0.83 / 1.90)
    EXPECT_LE(r.three_dof_max_rmse_deg, 3.0) << m;
  }
}

TEST(Accuracy, MagnetAndDeskWalk) {
  // The walk starts beside the magnet: measured 7.98 / 3.61 deg (seed 1; 15.5 worst hinge of
  // seeds 1..5 without the coupling), drift 8.0 %: missed, regression guards.
  AccuracyOptions o;
  o.motion = "walk";
  o.disturbance = "both";
  const AccuracyResult r = run_accuracy(o);
  ASSERT_TRUE(r.calibrated) << r.calibration_message;
  record(r);
  EXPECT_LE(r.hinge_max_rmse_deg, 10.0);
  EXPECT_LE(r.three_dof_max_rmse_deg, 4.5);
  EXPECT_LE(r.root_drift_fraction, 0.10);
}

TEST(Accuracy, MagnetAndDeskSquatAfterCalibrationMoves) {
  // Next to the magnet the N-pose takes the local field direction as a mounting yaw (20 deg on
  // the right forearm); the calibration moves identify it at the elbow. Measured (session 7,
  // seeds 1..5, hinge / 3-DOF): 2.24 / 4.54, 1.43 / 1.67, 1.45 / 3.25, 1.56 / 2.11,
  // 1.27 / 3.06 deg: seeds 2 and 4 meet every target; the rest are guarded ~15 % above.
  int met = 0;
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    AccuracyOptions o = after_moves("squat", seed);
    o.disturbance = "both";
    const AccuracyResult r = run_accuracy(o);
    ASSERT_TRUE(r.calibrated) << r.calibration_message;
    record(r);
    EXPECT_LE(r.hinge_max_rmse_deg, 2.6) << "seed " << seed;
    EXPECT_LE(r.three_dof_max_rmse_deg, 5.3) << "seed " << seed;
    met += r.hinge_max_rmse_deg <= 2.0 && r.three_dof_max_rmse_deg <= 3.0;
  }
  EXPECT_GE(met, 2);
}

TEST(Accuracy, UnknownDisturbanceIsRejected) {
  AccuracyOptions o;
  o.disturbance = "microwave";
  EXPECT_THROW(run_accuracy(o), std::invalid_argument);
}

}  // namespace
}  // namespace mocap::sim
