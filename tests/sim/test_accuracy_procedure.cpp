// Accuracy regression of the calibration procedure (N-pose + calibration moves), no disturbance:
// every built-in motion on seeds 1..5, the `moves/none` cells of scripts/accuracy-grid. The
// skeleton issue's targets (hinge <= 2 deg, 3-DOF <= 3 deg, root drift <= 5 %) are asserted on
// every cell. Measured (session 7, docs/accuracy.md "Verdict"): all 30 met, the closest turn
// seed 2 and sequence seed 2 (3-DOF 2.98 and 3.00 deg: the hip after 180 deg turns, the gyros'
// scale errors) and turn seed 4 (hinge 1.95).
// ~20 s in a release build; label slow (minutes under ASan).
#include <gtest/gtest.h>

#include <string>

#include "accuracy_test_util.hpp"
#include "mocap/sim/accuracy.hpp"

namespace mocap::sim {
namespace {

TEST(AccuracyProcedure, EveryMotionAfterTheCalibrationMovesMeetsTheTargets) {
  int met = 0, cells = 0;
  for (const char* motion : {"walk", "turn", "squat", "arm_raise", "reach", "sequence"}) {
    for (uint64_t seed = 1; seed <= 5; ++seed) {
      AccuracyOptions o = after_moves(motion, seed);
      const AccuracyResult r = run_accuracy(o);
      ASSERT_TRUE(r.calibrated) << motion << " seed " << seed << ": " << r.calibration_message;
      RecordProperty(
          std::string(motion) + "_seed" + std::to_string(seed),
          std::to_string(r.hinge_max_rmse_deg) + " / " + std::to_string(r.three_dof_max_rmse_deg));
      ++cells;
      EXPECT_LE(r.hinge_max_rmse_deg, 2.0) << motion << " seed " << seed;
      EXPECT_LE(r.three_dof_max_rmse_deg, 3.0) << motion << " seed " << seed;
      if (r.distance_walked_m >= 1.0) {
        EXPECT_LE(r.root_drift_fraction, 0.05) << motion << " seed " << seed;
      }
      EXPECT_EQ(r.hinges_identified, 4) << motion << " seed " << seed;
      met += r.hinge_max_rmse_deg <= 2.0 && r.three_dof_max_rmse_deg <= 3.0 &&
             (r.distance_walked_m < 1.0 || r.root_drift_fraction <= 0.05);
    }
  }
  RecordProperty("cells_meeting_every_target",
                 std::to_string(met) + " of " + std::to_string(cells));
  EXPECT_EQ(met, cells);
}

}  // namespace
}  // namespace mocap::sim
