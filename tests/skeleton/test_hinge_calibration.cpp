// Hinge-axis refinement of the calibration: per-segment yaw offsets of an N-pose calibration
// (wrong body heading, per-sensor filter heading offsets) are identified from knee and elbow
// motion and removed, so joint rotations come out right; without flexion nothing changes.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "mocap/skeleton/body_model.hpp"
#include "mocap/skeleton/hinge_calibration.hpp"
#include "mocap/skeleton/skeleton.hpp"
#include "skeleton_test_util.hpp"

namespace mocap {
namespace {

using test::kMs;

double angle_deg(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return 2 * std::acos(std::min(1.0, std::abs(a.dot(b)))) * kRadToDeg;
}

// Joint rotations of a person walking on the spot: pelvis turning and rocking, hips and
// shoulders swinging with some ab/adduction, knees and elbows flexing (pure hinges about y).
std::array<Eigen::Quaterniond, kSegmentCount> joints_at(double t, bool flex) {
  std::array<Eigen::Quaterniond, kSegmentCount> j;
  j.fill(Eigen::Quaterniond::Identity());
  const double w = 2 * M_PI * 0.9;
  j[0] = yaw_rotation(0.3 * std::sin(0.4 * t)) * axis_rotation(1, 0.1 * std::sin(w * t));
  j[index(Segment::torso)] = axis_rotation(1, 0.1 * std::sin(0.5 * t));
  for (int side = 0; side < 2; ++side) {
    const double ph = side * M_PI, sgn = side ? -1.0 : 1.0;
    const Segment thigh = side ? Segment::thigh_r : Segment::thigh_l;
    const Segment shank = side ? Segment::shank_r : Segment::shank_l;
    const Segment arm = side ? Segment::upper_arm_r : Segment::upper_arm_l;
    const Segment fore = side ? Segment::forearm_r : Segment::forearm_l;
    j[index(thigh)] = axis_rotation(1, -0.4 * std::sin(w * t + ph)) *
                      axis_rotation(0, sgn * 0.1 * std::sin(0.7 * t));
    j[index(arm)] = axis_rotation(1, 0.5 * std::sin(w * t + ph)) *
                    axis_rotation(0, sgn * 0.2 * (1 + std::sin(0.3 * t)));
    const double knee = flex ? 0.6 * (1 - std::cos(w * t + ph)) : 0.0;
    const double elbow = flex ? 0.7 * (1 - std::cos(0.8 * t + ph)) : 0.0;
    j[index(shank)] = axis_rotation(1, knee);
    j[index(fore)] = axis_rotation(1, -elbow);
  }
  return j;
}

struct HingeRig {
  std::array<Eigen::Quaterniond, kSegmentCount> q_sensor_segment;  // true mounting
  std::array<double, kSegmentCount> eps_rad{};  // per-sensor filter heading offset (earth yaw)
  Calibration calibration;                      // N-pose calibration with a wrong body heading
};

HingeRig make_setup(std::mt19937& rng, double heading_error_deg) {
  HingeRig s;
  std::normal_distribution<double> eps(0, 2 * kDegToRad);
  for (int i = 0; i < kSegmentCount; ++i) {
    s.q_sensor_segment[i] = test::random_rotation(rng);
    s.eps_rad[i] = eps(rng);
  }
  // The N-pose calibration (body facing yaw 0) as the Calibrator computes it, with its body
  // heading taken as heading_error_deg: mounting = mean^-1 Rz(heading).
  Calibration& c = s.calibration;
  c.valid = true;
  c.heading_deg = heading_error_deg;
  for (int i = 0; i < kSegmentCount; ++i) {
    const Eigen::Quaterniond mean = yaw_rotation(s.eps_rad[i]) * s.q_sensor_segment[i].conjugate();
    c.calibrated[i] = true;
    c.q_sensor_segment[i] = mean.conjugate() * yaw_rotation(heading_error_deg * kDegToRad);
  }
  return s;
}

struct RunResult {
  double knee_elbow_max_deg = 0;  // worst joint-rotation error of knees/elbows at the end
  double worst_joint_deg = 0;     // worst of all joints
  int valid_hinges = 0;
};

RunResult run(const HingeRig& s, bool refine, bool flex, std::mt19937& rng,
              Skeleton* out = nullptr) {
  SkeletonOptions opt;
  opt.hinge_refine.enabled = refine;
  Skeleton sk(BodyModel(BodyModelConfig{}), default_joint_limits(), RigMapping::full(), opt);
  sk.set_calibration(s.calibration);
  std::uniform_int_distribution<int> jitter_us(-2000, 2000);
  std::uniform_real_distribution<double> u(0, 1);
  PoseFrame frame;
  RunResult r;
  std::array<Eigen::Quaterniond, kSegmentCount> q_joint_true;
  for (int k = 0; k <= 1500; ++k) {  // 15 s at 100 Hz
    const int64_t t = k * 10 * kMs;
    q_joint_true = joints_at(t * 1e-9, flex);
    for (int i = 0; i < kSegmentCount; ++i) {
      if (u(rng) < 0.01) continue;  // dropped sample
      const int64_t ts = t + jitter_us(rng) * 1000;
      const auto q_earth = test::earth_from_joints(joints_at(ts * 1e-9, flex));
      const Eigen::Quaterniond q_sensor =
          yaw_rotation(s.eps_rad[i]) * q_earth[i] * s.q_sensor_segment[i].conjugate();
      sk.set_sensor_orientation(i, q_sensor, ts);
    }
    sk.solve(t, frame);
  }
  for (int i = 1; i < kSegmentCount; ++i) {
    const double e = angle_deg(sk.q_parent_segment()[i], q_joint_true[i]);
    r.worst_joint_deg = std::max(r.worst_joint_deg, e);
    if (is_hinge(static_cast<Segment>(i))) r.knee_elbow_max_deg = std::max(r.knee_elbow_max_deg, e);
  }
  r.valid_hinges = sk.hinge_refiner().valid_hinges();
  if (out) *out = sk;
  return r;
}

TEST(HingeCalibration, IdentifiesYawOffsetsAndCorrectsJoints) {
  std::mt19937 rng(7);
  const HingeRig s = make_setup(rng, 6.0);
  const RunResult before = run(s, false, true, rng);
  SkeletonOptions opt;
  Skeleton sk(BodyModel(BodyModelConfig{}), default_joint_limits(), RigMapping::full(), opt);
  const RunResult after = run(s, true, true, rng, &sk);
  // The wrong heading turns the knee/elbow axes: several degrees of error without refinement.
  EXPECT_GT(before.knee_elbow_max_deg, 3.0);
  EXPECT_EQ(after.valid_hinges, 4);
  EXPECT_LT(after.knee_elbow_max_deg, 0.6);
  EXPECT_LT(after.knee_elbow_max_deg, before.knee_elbow_max_deg / 5);
  EXPECT_LT(after.worst_joint_deg, before.worst_joint_deg);
  RecordProperty("knee_elbow_before_deg", std::to_string(before.knee_elbow_max_deg));
  RecordProperty("knee_elbow_after_deg", std::to_string(after.knee_elbow_max_deg));
  RecordProperty("worst_joint_before_deg", std::to_string(before.worst_joint_deg));
  RecordProperty("worst_joint_after_deg", std::to_string(after.worst_joint_deg));
  // Each refined segment's mounting yaw (vs the truth) is within 1 deg (the N-pose left up to
  // ~10 deg: heading error plus filter heading offsets).
  for (size_t h = 0; h < kRefineHingeCount; ++h) {
    for (int seg : {index(kRefinePairs[h].child), index(kRefinePairs[h].parent)}) {
      const Eigen::Quaterniond d =
          s.q_sensor_segment[seg].conjugate() * sk.calibration().q_sensor_segment[seg];
      const Eigen::Vector3d x = d * Eigen::Vector3d::UnitX();
      EXPECT_LT(std::abs(std::atan2(x.y(), x.x()) * kRadToDeg), 1.0) << kSegmentNames[seg];
    }
  }
  // The hands ride on the forearms (wrists still here): the elbow identifies them too.
  for (Segment hand : {Segment::hand_l, Segment::hand_r}) {
    const int seg = index(hand);
    const Eigen::Quaterniond d =
        s.q_sensor_segment[seg].conjugate() * sk.calibration().q_sensor_segment[seg];
    const Eigen::Vector3d x = d * Eigen::Vector3d::UnitX();
    EXPECT_LT(std::abs(std::atan2(x.y(), x.x()) * kRadToDeg), 1.0) << kSegmentNames[seg];
  }
  // The body heading is corrected too: the refined calibration's heading is near the truth (0).
  EXPECT_LT(std::abs(sk.calibration().heading_deg), 2.0);
  // Per-hinge diagnostics are filled.
  for (size_t h = 0; h < kRefineHingeCount; ++h) {
    EXPECT_TRUE(sk.hinge_refiner().hinges()[h].valid);
    EXPECT_GT(sk.hinge_refiner().hinges()[h].travel_deg, 150);
  }
}

TEST(HingeCalibration, NoFlexionLeavesTheCalibrationAlone) {
  std::mt19937 rng(8);
  const HingeRig s = make_setup(rng, 6.0);
  Skeleton sk(BodyModel(BodyModelConfig{}), default_joint_limits(), RigMapping::full(), {});
  run(s, true, false, rng, &sk);
  EXPECT_EQ(sk.hinge_refiner().valid_hinges(), 0);
  for (int i = 0; i < kSegmentCount; ++i) {
    EXPECT_TRUE(sk.calibration().q_sensor_segment[i].isApprox(s.calibration.q_sensor_segment[i]));
    EXPECT_TRUE(sk.calibration().q_correction[i].isApprox(Eigen::Quaterniond::Identity()));
  }
}

TEST(HingeCalibration, NewCalibrationRestartsTheRefinement) {
  std::mt19937 rng(9);
  const HingeRig s = make_setup(rng, 4.0);
  Skeleton sk(BodyModel(BodyModelConfig{}), default_joint_limits(), RigMapping::full(), {});
  run(s, true, true, rng, &sk);
  ASSERT_EQ(sk.hinge_refiner().valid_hinges(), 4);
  sk.set_calibration(s.calibration);
  EXPECT_EQ(sk.hinge_refiner().valid_hinges(), 0);
  EXPECT_TRUE(sk.calibration().q_sensor_segment[index(Segment::shank_l)].isApprox(
      s.calibration.q_sensor_segment[index(Segment::shank_l)]));
}

TEST(HingeCalibration, ApplyIsAConjugationPerSegment) {
  Calibration base;
  base.valid = true;
  base.calibrated.fill(true);
  std::array<double, kSegmentCount> alpha{};
  alpha[index(Segment::shank_l)] = 0.1;
  const Calibration c = HingeAxisRefiner::apply(base, alpha, 0.02);
  std::mt19937 rng(3);
  const Eigen::Quaterniond q = test::random_small_rotation(rng, 90);
  const int s = index(Segment::shank_l);
  // Rz(common - alpha) * q * Rz(alpha).
  const Eigen::Quaterniond expect = yaw_rotation(0.02 - 0.1) * q * yaw_rotation(0.1);
  EXPECT_LT(angle_deg(c.segment_from_sensor(s, q), expect), 1e-9);
  EXPECT_NEAR(c.heading_deg, 0.02 * kRadToDeg, 1e-12);
}

TEST(HingeCalibration, ApplyTurnsASegmentWithZeroOffsetByTheCommonYaw) {
  // An estimated offset of exactly 0 is an estimate like any other: the segment still takes the
  // common body-heading turn (it was once skipped as "no offset", leaving it yawed against all
  // the others by the common turn).
  Calibration base;
  base.valid = true;
  base.calibrated.fill(true);
  std::array<double, kSegmentCount> alpha{};
  alpha.fill(0.05);
  alpha[index(Segment::shank_r)] = 0.0;
  const Calibration c = HingeAxisRefiner::apply(base, alpha, 0.02);
  std::mt19937 rng(4);
  const Eigen::Quaterniond q = test::random_small_rotation(rng, 90);
  const int s = index(Segment::shank_r);
  EXPECT_LT(angle_deg(c.segment_from_sensor(s, q), yaw_rotation(0.02) * q), 1e-9);
}

TEST(HingeCalibration, EstimateIsContinuousInTheBaseHeading) {
  // Turning the base calibration's body heading by 0.01 deg turns every calibrated segment
  // frame about its vertical by 0.01 deg, so every yaw offset must move by -0.01 deg (the
  // refinement is equivariant). A finite search grid snapped to its nodes (0.05 deg) and,
  // in the long narrow valley of the cost where parent and child yaw are correlated, to points
  // degrees apart along the valley.
  std::array<std::array<HingeEstimate, kRefinePairs.size()>, 2> est;
  for (int k = 0; k < 2; ++k) {
    std::mt19937 rng(11);
    const HingeRig s = make_setup(rng, 5.0 + 0.01 * k);
    Skeleton sk(BodyModel(BodyModelConfig{}), default_joint_limits(), RigMapping::full(), {});
    run(s, true, true, rng, &sk);
    est[k] = sk.hinge_refiner().hinges();
  }
  for (size_t h = 0; h < kRefinePairs.size(); ++h) {
    ASSERT_TRUE(est[0][h].valid && est[1][h].valid) << h;
    EXPECT_NEAR(est[1][h].applied_child_yaw_deg - est[0][h].applied_child_yaw_deg, -0.01, 0.003)
        << h;
    if (est[0][h].parent_valid)
      EXPECT_NEAR(est[1][h].parent_yaw_deg - est[0][h].parent_yaw_deg, -0.01, 0.003) << h;
  }
}

}  // namespace
}  // namespace mocap
