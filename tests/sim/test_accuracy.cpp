// End-to-end accuracy regression: realistic consumer-MEMS sensors on the virtual performer,
// through our AttitudeFilter, N-pose calibration and the skeleton, against ground truth.
// Where the targets (elbow/knee <= 2 deg, 3-DOF <= 3 deg, root drift <= 5 %) are met they
// are asserted; where they are NOT met yet (realistic sensors: see docs/accuracy.md) the bound is a
// regression guard ~25 % above the measured value, named as such.
#include <gtest/gtest.h>

#include <cmath>

#include "mocap/sim/accuracy.hpp"

namespace mocap::sim {
namespace {

TEST(Accuracy, ArmRaiseThroughNinetyDegreesWithRealisticSensors) {
  AccuracyOptions o;
  o.motion = "arm_raise";
  const AccuracyResult r = run_accuracy(o);
  ASSERT_TRUE(r.calibrated) << r.calibration_message;
  EXPECT_GT(r.frames, 1000);
  RecordProperty("hinge_max_rmse_deg", std::to_string(r.hinge_max_rmse_deg));
  RecordProperty("three_dof_max_rmse_deg", std::to_string(r.three_dof_max_rmse_deg));
  // Measured 4.5 / 5.5 deg (seed 1): target missed, regression guard only.
  EXPECT_LE(r.hinge_max_rmse_deg, 5.5);
  EXPECT_LE(r.three_dof_max_rmse_deg, 7.0);
  for (int s = 0; s < kSegmentCount; ++s)
    EXPECT_TRUE(std::isfinite(r.segment_rmse_deg[s]));
}

TEST(Accuracy, WalkJointAnglesAndRootDrift) {
  AccuracyOptions o;
  o.motion = "walk";
  const AccuracyResult r = run_accuracy(o);
  ASSERT_TRUE(r.calibrated) << r.calibration_message;
  EXPECT_GT(r.distance_walked_m, 5.0);
  EXPECT_LE(r.root_drift_fraction, 0.05);  // target (measured 3.2 %)
  // Measured 2.40 / 2.20 deg (seed 1): 3-DOF meets its 3 deg target, the knee misses 2 deg.
  EXPECT_LE(r.hinge_max_rmse_deg, 3.0);
  EXPECT_LE(r.three_dof_max_rmse_deg, 3.0);
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
    EXPECT_LE(r.hinge_max_rmse_deg, 2.0) << m;  // target (measured <= 0.95)
    EXPECT_LE(r.three_dof_max_rmse_deg, 3.0) << m;
  }
}

TEST(Accuracy, UnknownDisturbanceIsRejected) {
  AccuracyOptions o;
  o.disturbance = "microwave";
  EXPECT_THROW(run_accuracy(o), std::invalid_argument);
}

}  // namespace
}  // namespace mocap::sim
