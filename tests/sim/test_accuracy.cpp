// End-to-end accuracy regression: realistic consumer-MEMS sensors on the virtual performer,
// through our AttitudeFilter, N-pose calibration (refined from knee/elbow motion) and the
// skeleton, against ground truth (seed 1; docs/accuracy.md has seeds 1..5).
// Where the targets (elbow/knee <= 2 deg, 3-DOF <= 3 deg, root drift <= 5 %) are met they
// are asserted; where they are NOT met (see docs/accuracy.md) the bound is a regression guard
// ~25 % above the measured value, named as such.
#include <gtest/gtest.h>

#include <cmath>

#include "mocap/sim/accuracy.hpp"

namespace mocap::sim {
namespace {

void record(const AccuracyResult& r) {
  testing::Test::RecordProperty(r.motion + "_" + r.disturbance + "_hinge_deg",
                                std::to_string(r.hinge_max_rmse_deg));
  testing::Test::RecordProperty(r.motion + "_" + r.disturbance + "_three_dof_deg",
                                std::to_string(r.three_dof_max_rmse_deg));
}

TEST(Accuracy, WalkJointAnglesAndRootDrift) {
  AccuracyOptions o;
  o.motion = "walk";
  const AccuracyResult r = run_accuracy(o);
  ASSERT_TRUE(r.calibrated) << r.calibration_message;
  record(r);
  EXPECT_GT(r.distance_walked_m, 5.0);
  EXPECT_LE(r.root_drift_fraction, 0.05);  // target (measured 2.2 %)
  // Targets, met: measured 1.41 / 1.35 deg (seeds 1..5: at most 1.91 / 2.34).
  EXPECT_LE(r.hinge_max_rmse_deg, 2.0);
  EXPECT_LE(r.three_dof_max_rmse_deg, 3.0);
  // The knees identified their axes during the walk.
  EXPECT_GE(r.hinges_identified, 2);
}

TEST(Accuracy, HingeRefinementRemovesTheCalibrationHeadingError) {
  // Without refinement the pelvis sensor's mount misalignment turns every joint axis (2.40 deg
  // knee); the refinement identifies each segment's mounting yaw from the knees (1.41 deg).
  AccuracyOptions o;
  o.motion = "walk";
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
  AccuracyOptions o;
  o.motion = "squat";
  o.calibration_moves = true;
  const AccuracyResult r = run_accuracy(o);
  ASSERT_TRUE(r.calibrated) << r.calibration_message;
  record(r);
  EXPECT_EQ(r.hinges_identified, 4);
  // Targets, met for seed 1: measured 1.68 / 2.06 deg (seeds 1..5: at most 2.53 / 3.00 —
  // hinge missed by seed 4, docs/accuracy.md).
  EXPECT_LE(r.hinge_max_rmse_deg, 2.0);
  EXPECT_LE(r.three_dof_max_rmse_deg, 3.0);
}

TEST(Accuracy, ArmRaiseThroughNinetyDegreesWithRealisticSensors) {
  AccuracyOptions o;
  o.motion = "arm_raise";
  o.calibration_moves = true;
  const AccuracyResult r = run_accuracy(o);
  ASSERT_TRUE(r.calibrated) << r.calibration_message;
  EXPECT_GT(r.frames, 1000);
  record(r);
  // Measured 2.82 / 2.10 deg (seed 1): 3-DOF meets its target for seed 1 (seeds 1..5: up to
  // 4.61); the elbow misses (the filters' heading drift between sensors, docs/accuracy.md):
  // regression guard only.
  EXPECT_LE(r.hinge_max_rmse_deg, 4.0);
  EXPECT_LE(r.three_dof_max_rmse_deg, 3.0);
  for (int s = 0; s < kSegmentCount; ++s)
    EXPECT_TRUE(std::isfinite(r.segment_rmse_deg[s]));
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
    EXPECT_LE(r.hinge_max_rmse_deg, 2.0) << m;  // target (measured <= 0.84 / 1.90)
    EXPECT_LE(r.three_dof_max_rmse_deg, 3.0) << m;
  }
}

TEST(Accuracy, MagnetAndDeskWalkWithHeadingHold) {
  // Magnet beside the right thigh + steel desk: the targets are missed (14-23 deg at the hinge
  // next to the magnet). Holding each flagged sensor's heading on its gyro more than halves the
  // walk's knee/elbow error: measured 14.3 -> 6.45 deg (seed 1). Regression guards.
  AccuracyOptions o;
  o.motion = "walk";
  o.disturbance = "both";
  const AccuracyResult plain = run_accuracy(o);
  o.heading_hold.enabled = true;
  const AccuracyResult held = run_accuracy(o);
  ASSERT_TRUE(plain.calibrated && held.calibrated);
  record(plain);
  record(held);
  EXPECT_LE(plain.hinge_max_rmse_deg, 18.0);
  EXPECT_LE(held.hinge_max_rmse_deg, 8.0);
  EXPECT_LT(held.hinge_max_rmse_deg, 0.6 * plain.hinge_max_rmse_deg);
  EXPECT_LE(held.root_drift_fraction, 0.11);  // measured 8.7 %: target (5 %) missed, guard
}

TEST(Accuracy, MagnetAndDeskSquatAfterCalibrationMovesWithHeadingHold) {
  // Next to the magnet the N-pose takes the local field direction as a mounting yaw (21 deg on
  // the right forearm); the calibration moves identify it at the elbow, the hold keeps the
  // gyro heading. Measured 1.48 / 5.04 deg (seed 1; plain pipeline 16.2 / 7.6): the hinge
  // meets its target for seed 1 (seeds 1..5: up to 2.61), 3-DOF misses (the hand beside the
  // magnet): guard.
  AccuracyOptions o;
  o.motion = "squat";
  o.disturbance = "both";
  o.calibration_moves = true;
  o.heading_hold.enabled = true;
  const AccuracyResult r = run_accuracy(o);
  ASSERT_TRUE(r.calibrated) << r.calibration_message;
  record(r);
  EXPECT_LE(r.hinge_max_rmse_deg, 2.0);
  EXPECT_LE(r.three_dof_max_rmse_deg, 6.3);
}

TEST(Accuracy, UnknownDisturbanceIsRejected) {
  AccuracyOptions o;
  o.disturbance = "microwave";
  EXPECT_THROW(run_accuracy(o), std::invalid_argument);
}

}  // namespace
}  // namespace mocap::sim
