// Procedural motions and the foot-planted root: smooth, start in the N-pose, feet do not slide.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "mocap/core/units.hpp"
#include "mocap/sim/motion.hpp"
#include "mocap/skeleton/joint_limits.hpp"

namespace mocap::sim {
namespace {

double angle_deg(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return Eigen::AngleAxisd(a.conjugate() * b).angle() * kDegPerRad;
}

TEST(Motion, EveryBuiltInStartsInTheNPoseAndIsFinite) {
  const auto dims = body_dimensions_from_height(1.75);
  const auto ref = reference_joint_positions(dims);
  for (auto name : motion_names()) {
    MotionTrack track(make_motion(name), dims, false);
    const auto [c0, c1] = track.motion().calibration_window_s();
    EXPECT_GE(c1 - c0, 2.9) << name;
    BodyPose pose;
    TruthFrame f;
    track.pose(0.5 * (c0 + c1), pose);
    truth_forward_kinematics(dims, pose, f);
    for (int i = 0; i < kSegmentCount; ++i) {
      EXPECT_LT(angle_deg(f.q_earth_segment[i], Eigen::Quaterniond::Identity()), 1e-9) << name;
      EXPECT_LT((f.p_earth_segment_m[i] - ref[i]).norm(), 1e-9) << name << " " << i;
    }
    for (double t = 0; t <= track.period_s(); t += 0.05) {
      track.pose(t, pose);
      truth_forward_kinematics(dims, pose, f);
      for (int i = 0; i < kSegmentCount; ++i) {
        ASSERT_TRUE(f.p_earth_segment_m[i].allFinite()) << name << " t=" << t;
        ASSERT_TRUE(f.q_earth_segment[i].coeffs().allFinite()) << name << " t=" << t;
      }
    }
  }
}

TEST(Motion, UnknownNameIsRejectedWithTheValidNames) {
  try {
    make_motion("moonwalk");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("moonwalk"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("walk"), std::string::npos);
  }
}

// "calibrate+<motion>": the stand, the calibration moves (knees and elbows flex, back to the
// N-pose), then the motion without its own leading stand.
TEST(Motion, CalibrationMovesPrecedeTheMotion) {
  const auto plain = make_motion("squat");
  const auto with = make_motion("calibrate+squat");
  EXPECT_NEAR(with->duration_s(), plain->duration_s() + calibration_moves_s(), 1e-9);
  EXPECT_EQ(with->calibration_window_s(), plain->calibration_window_s());
  const double t_moves = with->calibration_window_s().second;
  double max_knee_deg = 0, max_elbow_deg = 0;
  BodyPose p;
  for (double t = t_moves; t < t_moves + calibration_moves_s(); t += 0.01) {
    with->pose(t, p);
    max_knee_deg = std::max(max_knee_deg, angle_deg(p.q_parent_segment[index(Segment::shank_l)],
                                                    Eigen::Quaterniond::Identity()));
    max_elbow_deg = std::max(max_elbow_deg, angle_deg(p.q_parent_segment[index(Segment::forearm_r)],
                                                      Eigen::Quaterniond::Identity()));
  }
  EXPECT_GT(max_knee_deg, 50);
  EXPECT_GT(max_elbow_deg, 80);
  // After the moves: the squat, in step with the plain motion after its stand.
  BodyPose a, b;
  with->pose(t_moves + calibration_moves_s() + 2.0, a);
  plain->pose(t_moves + 2.0, b);
  EXPECT_LT(angle_deg(a.q_parent_segment[index(Segment::shank_l)],
                      b.q_parent_segment[index(Segment::shank_l)]),
            1e-9);
  EXPECT_THROW(make_motion("calibrate+npose"), std::invalid_argument);
  EXPECT_THROW(make_motion("calibrate+moonwalk"), std::invalid_argument);
}

// "warmup+": the sensors run through a walk there and back before the calibration stand, which
// (and everything after it) is the motion without the prefix, shifted.
TEST(Motion, WarmupWalksBeforeTheCalibrationStand) {
  const auto plain = make_motion("calibrate+squat");
  const auto warm = make_motion("warmup+calibrate+squat");
  const double shift_s = warm->duration_s() - plain->duration_s();
  EXPECT_NEAR(shift_s, 22.4, 1e-9);
  EXPECT_NEAR(warm->calibration_window_s().first, shift_s, 1e-9);
  EXPECT_NEAR(warm->calibration_window_s().second, shift_s + 3.0, 1e-9);
  double max_knee_deg = 0;
  BodyPose p, a, b;
  for (double t = 0; t < shift_s; t += 0.05) {
    warm->pose(t, p);
    max_knee_deg = std::max(max_knee_deg, angle_deg(p.q_parent_segment[index(Segment::shank_l)],
                                                    Eigen::Quaterniond::Identity()));
  }
  EXPECT_GT(max_knee_deg, 40);  // walking
  for (double t = 0; t < plain->duration_s(); t += 0.37) {
    warm->pose(t + shift_s, a);
    plain->pose(t, b);
    EXPECT_LT(angle_deg(a.q_earth_pelvis, b.q_earth_pelvis), 1e-6) << t;  // facing as before
    EXPECT_LT(angle_deg(a.q_parent_segment[index(Segment::shank_l)],
                        b.q_parent_segment[index(Segment::shank_l)]),
              1e-9);
  }
  EXPECT_THROW(make_motion("calibrate+warmup+squat"), std::invalid_argument);
}

// Lowest contact point (heel below the ankle, or toe = foot end point) of a foot.
// With `point` >= 0 the same point (0 heel, 1 toe) is returned, else the lower one.
Eigen::Vector3d contact(const BodyDimensions& d, const TruthFrame& f, Segment foot,
                        int* chosen = nullptr, int point = -1) {
  const int i = index(foot);
  const double ankle_h = reference_joint_positions(d)[i].z();
  const Eigen::Vector3d heel =
      f.p_earth_segment_m[i] + f.q_earth_segment[i] * Eigen::Vector3d(0, 0, -ankle_h);
  const Eigen::Vector3d toe = f.p_earth_segment_m[i] + f.q_earth_segment[i] * d.end_offset_m[i];
  if (point < 0) point = heel.z() < toe.z() ? 0 : 1;
  if (chosen) *chosen = point;
  return point == 0 ? heel : toe;
}

TEST(Motion, WalkAdvancesWithAPlantedStanceFoot) {
  const auto dims = body_dimensions_from_height(1.75);
  MotionTrack track(make_motion("walk"), dims, false);
  BodyPose pose;
  TruthFrame a, b;
  const double h = 0.005;
  int stance_checks = 0;
  double min_z = 1;
  for (double t = 4.0; t < 10.0; t += h) {
    track.pose(t, pose);
    truth_forward_kinematics(dims, pose, a);
    track.pose(t + h, pose);
    truth_forward_kinematics(dims, pose, b);
    const Eigen::Vector3d l = contact(dims, a, Segment::foot_l);
    const Eigen::Vector3d r = contact(dims, a, Segment::foot_r);
    min_z = std::min({min_z, l.z(), r.z()});
    if (std::abs(l.z() - r.z()) < 0.03) continue;  // double support: weight is handed over
    const Segment stance = l.z() < r.z() ? Segment::foot_l : Segment::foot_r;
    int point = 0;
    const Eigen::Vector3d c0 = contact(dims, a, stance, &point);
    const Eigen::Vector3d c1 = contact(dims, b, stance, nullptr, point);
    EXPECT_NEAR(c0.z(), 0.0, 0.003) << "stance foot off the floor at t=" << t;
    EXPECT_LT((c1 - c0).head<2>().norm() / h, 0.05) << "stance contact slides at t=" << t;
    ++stance_checks;
  }
  EXPECT_GT(stance_checks, 400);
  EXPECT_GT(min_z, -0.003);  // nothing goes through the floor
  track.pose(track.period_s(), pose);
  // About 1 m/s over most of 8.8 s of walking, straight ahead (+x).
  EXPECT_GT(pose.p_earth_pelvis_m.x(), 6.0);
  EXPECT_LT(std::abs(pose.p_earth_pelvis_m.y()), 0.2);
}

// The walk's ankles (and every other joint) stay within the body model's joint limits over the
// whole motion, checked with the skeleton's checker on the true joint rotations: the swing foot
// points toe-down after toe-off instead of staying level (which dorsiflexed the ankle ~60 deg).
TEST(Motion, WalkJointsStayWithinTheJointLimits) {
  const auto dims = body_dimensions_from_height(1.75);
  const JointLimits limits = default_joint_limits();
  MotionTrack track(make_motion("walk"), dims, false);
  BodyPose pose;
  TruthFrame f;
  double worst_deg = 0, max_dorsi_deg = 0, max_plantar_deg = 0;
  for (double t = 0; t <= track.period_s(); t += 0.005) {
    track.pose(t, pose);
    truth_forward_kinematics(dims, pose, f);
    for (int s = 1; s < kSegmentCount; ++s) {
      const JointCheck c = check_joint(limits.joint[s], f.q_parent_segment[s]);
      worst_deg = std::max(worst_deg, c.violation_deg);
      if (s == index(Segment::foot_l) || s == index(Segment::foot_r)) {
        max_dorsi_deg = std::max(max_dorsi_deg, -c.b_deg);
        max_plantar_deg = std::max(max_plantar_deg, c.b_deg);
      }
    }
  }
  std::printf(
      "walk: worst joint-limit violation %.2g deg, ankle dorsiflexion up to %.1f deg, "
      "plantarflexion up to %.1f deg\n",
      worst_deg, max_dorsi_deg, max_plantar_deg);
  EXPECT_LT(worst_deg, 1e-6);
  // Within the open-chain (unloaded) dorsiflexion range of 20 deg too, the swing foot's range,
  // not only the weight-bearing 35 of the model; and the ankle really moves (not frozen).
  EXPECT_LT(max_dorsi_deg, 20);
  EXPECT_GT(max_dorsi_deg, 10);
  EXPECT_GT(max_plantar_deg, 10);
}

// Every built-in motion, after the calibration procedure (N-pose, knee bends, elbow curls),
// keeps every joint within the body model's default limits, so the demo's avatar is never
// flagged or clamped for what the truth does; the squat and the knee bends (feet flat, shank
// inclined 25 deg) dorsiflex the ankle 25 deg, within its weight-bearing 35; the reach crosses
// the body with 32 deg of shoulder adduction, within 45.
TEST(Motion, EveryBuiltInStaysWithinTheJointLimits) {
  const auto dims = body_dimensions_from_height(1.75);
  const JointLimits limits = default_joint_limits();
  BodyPose pose;
  TruthFrame f;
  for (std::string_view name : motion_names()) {
    if (name == "npose") continue;
    MotionTrack track(make_motion("calibrate+" + std::string(name)), dims, false);
    double worst_deg = 0, worst_t = 0;
    int worst_segment = 0;
    for (double t = 0; t <= track.period_s(); t += 0.01) {
      track.pose(t, pose);
      truth_forward_kinematics(dims, pose, f);
      for (int s = 1; s < kSegmentCount; ++s) {
        const double v = check_joint(limits.joint[s], f.q_parent_segment[s]).violation_deg;
        if (v > worst_deg) {
          worst_deg = v;
          worst_segment = s;
          worst_t = t;
        }
      }
    }
    EXPECT_LT(worst_deg, 1e-6) << name << ": " << kJointNames[worst_segment] << " " << worst_deg
                               << " deg outside at t = " << worst_t << " s";
  }
}

// Toe clearance: while the swing foot passes the stance foot (their ankles within 15 cm along
// the walking direction x) its lowest point (heel or pitched toe) is 1..6 cm above the floor,
// like a real swing foot (minimum toe clearance ~1-2 cm); it never scuffs the floor then.
TEST(Motion, WalkSwingFootClearsTheFloorLikeARealFoot) {
  const auto dims = body_dimensions_from_height(1.75);
  MotionTrack track(make_motion("walk"), dims, false);
  BodyPose pose;
  TruthFrame f;
  double min_clearance = 1, max_clearance = 0;
  int passing = 0;
  for (double t = 5.0; t < 10.0; t += 0.005) {
    track.pose(t, pose);
    truth_forward_kinematics(dims, pose, f);
    const Eigen::Vector3d l = contact(dims, f, Segment::foot_l);
    const Eigen::Vector3d r = contact(dims, f, Segment::foot_r);
    const bool left_swing = l.z() > r.z();
    const Eigen::Vector3d swing = left_swing ? l : r, stance = left_swing ? r : l;
    const double dx = f.p_earth_segment_m[index(Segment::foot_l)].x() -
                      f.p_earth_segment_m[index(Segment::foot_r)].x();
    if (std::abs(dx) > 0.15 || stance.z() > 0.003) continue;
    ++passing;
    min_clearance = std::min(min_clearance, swing.z());
    max_clearance = std::max(max_clearance, swing.z());
  }
  std::printf("swing foot clearance while passing: %.3f .. %.3f m\n", min_clearance, max_clearance);
  EXPECT_GT(passing, 50);
  EXPECT_GT(min_clearance, 0.01);
  EXPECT_LT(max_clearance, 0.06);
}

TEST(Motion, LoopContinuesWhereThePreviousLoopEnded) {
  const auto dims = body_dimensions_from_height(1.75);
  MotionTrack track(make_motion("turn"), dims, true);
  BodyPose before, after;
  const double T = track.period_s();
  track.pose(T - 1e-6, before);
  track.pose(T + 1e-6, after);
  EXPECT_LT((before.p_earth_pelvis_m - after.p_earth_pelvis_m).norm(), 1e-4);
  EXPECT_LT(angle_deg(before.q_earth_pelvis, after.q_earth_pelvis), 1e-3);
  // After a second 180-degree turn the performer faces forward again.
  track.pose(2 * T, after);
  EXPECT_LT(angle_deg(after.q_earth_pelvis, Eigen::Quaterniond::Identity()), 1e-6);
}

}  // namespace
}  // namespace mocap::sim
