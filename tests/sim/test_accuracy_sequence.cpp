// Accuracy regression on the 56 s sequence (walk, turn, squat, arm raise, reach strung together),
// with and without the magnet: the heading coupling at the knees and elbows is what holds its
// hinges. Separate from test_accuracy.cpp and labelled slow: ~8 s here, minutes under ASan.
#include <gtest/gtest.h>

#include "accuracy_test_util.hpp"
#include "mocap/sim/accuracy.hpp"

namespace mocap::sim {
namespace {

TEST(Accuracy, HeadingCouplingHoldsTheSequencesHinges) {
  // The 56 s sequence: each sensor's filter heading drifted its own way as it turned (hard-iron
  // residuals). The filters now learn the residual during the motion and keep the heading
  // error the N-pose calibration absorbed (AttitudeFilter::anchor_heading): 3-DOF 3.46 -> 2.49
  // (seed 1), 4.55 -> 2.75 (seed 3), targets met; hinges 1.68 / 1.35 with the coupling at the
  // knees/elbows (without it 1.70 / 1.56: it no longer has much drift to hold).
  for (uint64_t seed : {1, 3}) {
    AccuracyOptions o;
    o.motion = "sequence";
    o.seed = seed;
    const AccuracyResult r = run_accuracy(o);
    ASSERT_TRUE(r.calibrated) << r.calibration_message;
    record(r);
    EXPECT_LE(r.hinge_max_rmse_deg, 2.0) << seed;
    EXPECT_LE(r.three_dof_max_rmse_deg, 3.0) << seed;
    EXPECT_LE(r.root_drift_fraction, 0.05) << seed;  // target (measured 0.8 %, 2.0 %)
    if (seed == 1) {
      o.anchor_heading = false;  // the offset learnt after the calibration turns it
      const AccuracyResult unanchored = run_accuracy(o);
      EXPECT_LT(r.three_dof_max_rmse_deg, unanchored.three_dof_max_rmse_deg - 0.7);
      o.anchor_heading = true;
      o.heading_coupling.enabled = false;
      const AccuracyResult uncoupled = run_accuracy(o);
      EXPECT_LE(uncoupled.hinge_max_rmse_deg, 2.0);
    }
  }
}

TEST(Accuracy, MagnetAndDeskSequenceWithHeadingCoupling) {
  // Magnet beside the right thigh at the start + steel desk. The rig consensus of the reference
  // field and the trust anchor (filter) keep the right forearm and hand from taking the
  // magnet's field as north (uncoupled 21.9 -> 3.6 deg, seed 1); the coupling still holds the
  // forearm to the upper arm: 3.6 -> 2.86. Still missed: regression guards.
  AccuracyOptions o;
  o.motion = "sequence";
  o.disturbance = "both";
  const AccuracyResult r = run_accuracy(o);
  o.heading_coupling.enabled = false;
  const AccuracyResult uncoupled = run_accuracy(o);
  ASSERT_TRUE(r.calibrated && uncoupled.calibrated);
  record(r);
  EXPECT_LE(r.hinge_max_rmse_deg, 3.6);          // measured 2.86
  EXPECT_LE(r.three_dof_max_rmse_deg, 5.0);      // measured 3.98
  EXPECT_LE(r.root_drift_fraction, 0.05);        // target (measured 0.8 %)
  EXPECT_LE(uncoupled.hinge_max_rmse_deg, 4.5);  // measured 3.60 (21.9 before the consensus)
  EXPECT_LT(r.hinge_max_rmse_deg, 0.9 * uncoupled.hinge_max_rmse_deg);
}

}  // namespace
}  // namespace mocap::sim
