// Root motion on a realistic gait: the skeleton fed the simulated performer's TRUE segment
// orientations (the walk's swing foot points toe-down after toe-off, as a real one does) moves
// its root with the true pelvis within a small fraction of the distance walked.
#include <gtest/gtest.h>

#include <cstdio>

#include "mocap/sim/motion.hpp"
#include "mocap/skeleton/skeleton.hpp"

namespace mocap {
namespace {

struct WalkResult {
  double drift_m = 0, walked_m = 0, worst_error_m = 0;
  int stance_switches = 0;
};

// Solves the walk at 100 Hz from the truth's orientations, the root reset to the true pelvis
// when the walk starts (after the 3 s N-pose stand).
WalkResult walk_with(const RootMotionOptions& root) {
  const auto dims = body_dimensions_from_height(1.75);
  const BodyModel model(dims);
  sim::MotionTrack track(sim::make_motion("walk"), dims, false);
  SkeletonOptions o;
  o.root = root;
  Skeleton sk(model, default_joint_limits(), RigMapping::full(), o);
  sim::BodyPose pose;
  sim::TruthFrame truth;
  PoseFrame f;
  WalkResult r;
  Eigen::Vector3d prev_true = Eigen::Vector3d::Zero();
  int prev_stance = -1;
  const double start_s = 3.0, dt_s = 0.01;
  for (int k = 0; k * dt_s <= track.period_s(); ++k) {
    const double t = k * dt_s;
    track.pose(t, pose);
    sim::truth_forward_kinematics(dims, pose, truth);
    const int64_t t_ns = static_cast<int64_t>(k) * 10'000'000;
    for (int s = 0; s < kSegmentCount; ++s)
      sk.set_sensor_orientation(s, truth.q_earth_segment[s], t_ns);
    sk.solve(t_ns, f);
    const Eigen::Vector3d p_true = truth.p_earth_segment_m[0];
    if (t < start_s) {
      sk.root_motion().reset(p_true);
      prev_true = p_true;
      continue;
    }
    r.walked_m += (p_true - prev_true).head<2>().norm();
    prev_true = p_true;
    const double e = (sk.p_earth_segment_m()[0] - p_true).head<2>().norm();
    r.worst_error_m = std::max(r.worst_error_m, e);
    r.drift_m = e;
    const int stance = sk.root_motion().stance_foot();
    if (prev_stance >= 0 && stance != prev_stance) ++r.stance_switches;
    prev_stance = stance;
  }
  return r;
}

TEST(RootMotionGait, TracksTheTruePelvisOnAToeDownSwing) {
  const WalkResult r = walk_with({});
  EXPECT_GT(r.walked_m, 6.0);
  // About 15 steps in 8.8 s: each one a single stance switch (no flicker).
  EXPECT_GE(r.stance_switches, 13);
  EXPECT_LE(r.stance_switches, 17);
  EXPECT_LT(r.drift_m, 0.02 * r.walked_m) << r.drift_m << " m over " << r.walked_m << " m";
  EXPECT_LT(r.worst_error_m, 0.03 * r.walked_m);
}

// Without the toe-off timing the anchor rides on the lifting, toe-down swing foot until the
// height hysteresis is reached, and the root falls behind by centimetres per step.
TEST(RootMotionGait, ToeOffTimingIsWhatKeepsTheRootOnTrack) {
  RootMotionOptions off;
  off.lift_rate_m_s = 0;
  const WalkResult with = walk_with({}), without = walk_with(off);
  std::printf("root drift with toe-off timing %.3f m, without %.3f m, over %.2f m walked\n",
              with.drift_m, without.drift_m, with.walked_m);
  EXPECT_GT(without.drift_m, 3 * with.drift_m);
  EXPECT_GT(without.drift_m, 0.04 * without.walked_m);
}

}  // namespace
}  // namespace mocap
