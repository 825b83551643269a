// Accuracy regression of the calibration procedure (N-pose + calibration moves), no disturbance:
// every built-in motion on seeds 1..5, the `moves/none` cells of scripts/accuracy-grid. The
// skeleton issue's targets (hinge <= 2 deg, 3-DOF <= 3 deg, root drift <= 5 %) are asserted on
// every cell. Measured (session 7, docs/accuracy.md "Verdict"): all 30 met, the closest turn
// seed 2 and sequence seed 2 (3-DOF 2.98 and 3.00 deg: the hip after 180 deg turns, the gyros'
// scale errors) and turn seed 4 (hinge 1.95). With the gyro scale calibrated (session 8) every
// cell keeps 10 % below every target.
// ~40 s in a release build; label slow (minutes under ASan).
#include <gtest/gtest.h>

#include <string>

#include "accuracy_test_util.hpp"
#include "mocap/sim/accuracy.hpp"

namespace mocap::sim {
namespace {

/// Runs the 30 cells; asserts each figure <= margin x its target. Returns the cells meeting
/// every target.
int run_cells(bool gyro_scale_calibration, double margin) {
  int met = 0;
  for (const char* motion : {"walk", "turn", "squat", "arm_raise", "reach", "sequence"}) {
    for (uint64_t seed = 1; seed <= 5; ++seed) {
      AccuracyOptions o = after_moves(motion, seed);
      o.gyro_scale_calibration = gyro_scale_calibration;
      const AccuracyResult r = run_accuracy(o);
      EXPECT_TRUE(r.calibrated) << motion << " seed " << seed << ": " << r.calibration_message;
      testing::Test::RecordProperty(
          std::string(motion) + "_seed" + std::to_string(seed),
          std::to_string(r.hinge_max_rmse_deg) + " / " + std::to_string(r.three_dof_max_rmse_deg));
      EXPECT_LE(r.hinge_max_rmse_deg, margin * 2.0) << motion << " seed " << seed;
      EXPECT_LE(r.three_dof_max_rmse_deg, margin * 3.0) << motion << " seed " << seed;
      if (r.distance_walked_m >= 1.0) {
        EXPECT_LE(r.root_drift_fraction, margin * 0.05) << motion << " seed " << seed;
      }
      EXPECT_EQ(r.hinges_identified, 4) << motion << " seed " << seed;
      met += r.hinge_max_rmse_deg <= 2.0 && r.three_dof_max_rmse_deg <= 3.0 &&
             (r.distance_walked_m < 1.0 || r.root_drift_fraction <= 0.05);
    }
  }
  testing::Test::RecordProperty("cells_meeting_every_target", std::to_string(met) + " of 30");
  return met;
}

TEST(AccuracyProcedure, EveryMotionAfterTheCalibrationMovesMeetsTheTargets) {
  EXPECT_EQ(run_cells(false, 1.0), 30);
}

// With each sensor's one-time gyro scale calibration (table spins, `mocap gyro-scale`): every
// cell within 90 % of each target (measured worst: hinge 1.71, 3-DOF 2.35, drift 4.31 %).
TEST(AccuracyProcedure, WithGyroScaleCalibrationEveryCellHasATenPercentMargin) {
  EXPECT_EQ(run_cells(true, 0.9), 30);
}

}  // namespace
}  // namespace mocap::sim
