// Hinge-axis refinement of the calibration: per-segment yaw offsets of an N-pose calibration
// (wrong body heading, per-sensor filter heading offsets) are identified from knee and elbow
// motion and removed, so joint rotations come out right; without flexion nothing changes.
#include <gtest/gtest.h>

#include <algorithm>
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
// With `curls` instead: the arms hanging (slow ab/adduction only) while the elbows curl, the
// wrists straight for 5 s, then following the elbows: flexion along the elbow's axis (0.3 of
// the elbow's angle) and deviation off it (0.12), as in a curl with the hand following.
std::array<Eigen::Quaterniond, kSegmentCount> joints_at(double t, bool flex, bool curls = false) {
  std::array<Eigen::Quaterniond, kSegmentCount> j;
  j.fill(Eigen::Quaterniond::Identity());
  const double w = 2 * M_PI * 0.9;
  j[0] = yaw_rotation(0.3 * std::sin(0.4 * t)) * axis_rotation(1, 0.1 * std::sin(w * t));
  j[index(Segment::torso)] = axis_rotation(1, 0.1 * std::sin(0.5 * t));
  // The wrists' share of the elbow's angle: 0 until 5 s, then a smooth ramp to 1 at 7 s.
  const double x = std::clamp((t - 5) / 2, 0.0, 1.0), wrist = curls ? x * x * (3 - 2 * x) : 0.0;
  for (int side = 0; side < 2; ++side) {
    const double ph = side * M_PI, sgn = side ? -1.0 : 1.0;
    const Segment thigh = side ? Segment::thigh_r : Segment::thigh_l;
    const Segment shank = side ? Segment::shank_r : Segment::shank_l;
    const Segment arm = side ? Segment::upper_arm_r : Segment::upper_arm_l;
    const Segment fore = side ? Segment::forearm_r : Segment::forearm_l;
    const Segment hand = side ? Segment::hand_r : Segment::hand_l;
    j[index(thigh)] = axis_rotation(1, -0.4 * std::sin(w * t + ph)) *
                      axis_rotation(0, sgn * 0.1 * std::sin(0.7 * t));
    j[index(arm)] = axis_rotation(1, (curls ? 0.0 : 0.5) * std::sin(w * t + ph)) *
                    axis_rotation(0, sgn * 0.2 * (1 + std::sin(0.3 * t)));
    const double knee = flex && !curls ? 0.6 * (1 - std::cos(w * t + ph)) : 0.0;
    const double elbow = flex ? 0.7 * (1 - std::cos((curls ? 1.6 : 0.8) * t + ph)) : 0.0;
    j[index(shank)] = axis_rotation(1, knee);
    j[index(fore)] = axis_rotation(1, -elbow);
    j[index(hand)] =
        axis_rotation(1, -0.3 * wrist * elbow) * axis_rotation(0, sgn * 0.12 * wrist * elbow);
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

RunResult run(const HingeRig& s, bool refine, bool flex, std::mt19937& rng, Skeleton* out = nullptr,
              bool curls = false, HingeRefineOptions refine_opt = {}) {
  SkeletonOptions opt;
  opt.hinge_refine = refine_opt;
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
    q_joint_true = joints_at(t * 1e-9, flex, curls);
    for (int i = 0; i < kSegmentCount; ++i) {
      if (u(rng) < 0.01) continue;  // dropped sample
      const int64_t ts = t + jitter_us(rng) * 1000;
      const auto q_earth = test::earth_from_joints(joints_at(ts * 1e-9, flex, curls));
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

double mount_yaw_error_deg(const HingeRig& s, const Skeleton& sk, Segment seg) {
  const Eigen::Quaterniond d =
      s.q_sensor_segment[index(seg)].conjugate() * sk.calibration().q_sensor_segment[index(seg)];
  const Eigen::Vector3d x = d * Eigen::Vector3d::UnitX();
  return std::atan2(x.y(), x.x()) * kRadToDeg;
}

// Wrists flexing and deviating with the elbows while the arms hang: the hand's fit through the
// elbow admits samples whose wrist rate is below via_still_fraction of the elbow's, and their
// deviation off the elbow's axis tilts the hand's apparent axis. The noise weighting gives
// those blocks (inconsistent with a rigid wrist) little weight against the clean curls of the
// first 5 s. (A strict gate on the wrist's rate off the elbow's axis, built and measured
// alongside, fixed this too but added one grid target on top of the weighting: not kept,
// docs/accuracy.md "The wrist".)
TEST(HingeCalibration, WristMovingWithTheElbowDoesNotBiasTheHand) {
  std::mt19937 rng(7);
  const HingeRig s = make_setup(rng, 6.0);
  SkeletonOptions opt;
  Skeleton weighted(BodyModel(BodyModelConfig{}), default_joint_limits(), RigMapping::full(), opt);
  Skeleton unweighted = weighted;
  std::mt19937 rng_a(11), rng_b(11);
  run(s, true, true, rng_a, &weighted, true);
  HingeRefineOptions no_weighting;
  no_weighting.noise_weighting = false;
  run(s, true, true, rng_b, &unweighted, true, no_weighting);
  for (Segment hand : {Segment::hand_l, Segment::hand_r}) {
    const double e_weighted = mount_yaw_error_deg(s, weighted, hand);
    const double e_unweighted = mount_yaw_error_deg(s, unweighted, hand);
    RecordProperty(std::string(kSegmentNames[index(hand)]) + "_yaw_error_deg",
                   std::to_string(e_weighted));
    RecordProperty(std::string(kSegmentNames[index(hand)]) + "_unweighted_yaw_error_deg",
                   std::to_string(e_unweighted));
    // Measured: hand_l 0.25, hand_r -0.09 deg (unweighted: 4.54, -4.80).
    EXPECT_LT(std::abs(e_weighted), 1.0) << kSegmentNames[index(hand)];
    EXPECT_LT(std::abs(e_weighted), std::abs(e_unweighted) / 4) << kSegmentNames[index(hand)];
    // The scenario does bias the unweighted fit (else this test would prove nothing).
    EXPECT_GT(std::abs(e_unweighted), 3.0) << kSegmentNames[index(hand)];
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
    if (est[0][h].parent_valid) {
      EXPECT_NEAR(est[1][h].parent_yaw_deg - est[0][h].parent_yaw_deg, -0.01, 0.003) << h;
    }
  }
}

// A child-yaw cost (parent fixed at 0) with two minima 9.5 deg apart, at y0 -+ 4.75 deg,
// separated by a bump at y0 of 2 d (1 - cos 9.5 deg)^2 = 7.5 % of the cost (~1); `tilt` lowers the
// minimum at y0 + 4.75 by 2 sin(9.5 deg) tilt = 0.33 tilt: cost = d + d cos 2w + B cos w + tilt
// sin w + s, w = fc - 2 y0.
struct DoubleWell {
  Eigen::Matrix4d h = Eigen::Matrix4d::Zero();
  Eigen::Vector4d g = Eigen::Vector4d::Zero();
  double s = 0;
};
DoubleWell double_well(double y0_deg, double tilt) {
  // Minima at w = 180 +- 9.5 deg (y = y0 -+ 4.75 deg): 9.5 deg apart, so they sit differently
  // between the 1 deg grid nodes.
  const double d = 200, u = 9.5 * kDegToRad, b = 4 * d * std::cos(u), th = 2 * y0_deg * kDegToRad;
  DoubleWell w;
  w.h.bottomRightCorner<2, 2>() << d * (1 + std::cos(2 * th)), d * std::sin(2 * th),
      d * std::sin(2 * th), d * (1 - std::cos(2 * th));
  w.g.tail<2>() << 0.5 * (b * std::cos(th) - tilt * std::sin(th)),
      0.5 * (b * std::sin(th) + tilt * std::cos(th));
  // Lowest value of the untilted cost (d + d cos 2u - b cos u) -> 1.
  w.s = 1 - (d + d * std::cos(2 * u) - b * std::cos(u));
  return w;
}
// The hysteresis margin measured on the accuracy grid (docs/accuracy.md; opt-in).
constexpr double kBasinMargin = 0.02;
HingeAxisRefiner::YawFit fit_well(const DoubleWell& w, double ref_deg, double margin) {
  return HingeAxisRefiner::fit(w.h, w.g, w.s, 40 * kDegToRad, true, 0, 0, ref_deg * kDegToRad,
                               margin);
}

TEST(HingeCalibration, NearEqualMinimaKeepTheBasinInUse) {
  // The ambiguous elbow fit (docs/accuracy.md): two minima ~5-10 deg apart whose costs differ by
  // a fraction of a percent. Which one wins must not depend on where the search grid's nodes fall
  // (a heading change of 0.01 deg shifts the cost against the grid) nor on which of the two is
  // lower by 0.01 % this half second: the offset in use (here the N-pose value 0, then each
  // result) is kept while the data do not separate the basins.
  const double margin = kBasinMargin;
  {  // Both minima exist, the far one (+6 deg) slightly lower.
    const DoubleWell w = double_well(1.0, 0.001);
    const auto far = fit_well(w, 5.75, margin), near = fit_well(w, 0.0, margin);
    EXPECT_NEAR(far.yaw_c * kRadToDeg, 5.75, 0.3);
    EXPECT_NEAR(near.yaw_c * kRadToDeg, -3.75, 0.3);
    EXPECT_GT(near.cost, far.cost);
    EXPECT_LT(near.cost, far.cost * 1.002);
    EXPECT_NEAR(fit_well(w, 0.0, 0).yaw_c * kRadToDeg, 5.75, 0.3);  // margin 0: the lowest
  }
  // The landscape shifted by 0.01 deg steps over 1 deg while its tilt swings across zero (the
  // lower minimum alternates): the result follows its basin continuously.
  double ref_deg = 0;
  for (int k = 0; k <= 100; ++k) {
    const double shift_deg = 0.01 * k, tilt = 0.002 * std::sin(0.7 * k);
    const auto f = fit_well(double_well(1.0 + shift_deg, tilt), ref_deg, margin);
    ASSERT_NEAR(f.yaw_c * kRadToDeg, -3.75 + shift_deg, 0.3) << k;
    ref_deg = f.yaw_c * kRadToDeg;
  }
  // Without the margin it jumps between the basins.
  int jumps = 0;
  ref_deg = 0;
  for (int k = 0; k <= 100; ++k) {
    const double tilt = 0.002 * std::sin(0.7 * k);
    const auto f = fit_well(double_well(1.0 + 0.01 * k, tilt), ref_deg, 0);
    if (k > 0 && std::abs(f.yaw_c * kRadToDeg - ref_deg) > 5) ++jumps;
    ref_deg = f.yaw_c * kRadToDeg;
  }
  EXPECT_GT(jumps, 10);
  // The former search (the basin of the grid's lowest node, margin < 0) jumps with the shift
  // alone, the costs fixed: where the nodes fall decides.
  jumps = 0;
  double prev_deg = 0;
  for (int k = 0; k <= 100; ++k) {
    const double shift_deg = 0.01 * k;
    const auto f = fit_well(double_well(1.0 + shift_deg, 0.0002), 0, -1);
    if (k > 0 && std::abs(f.yaw_c * kRadToDeg - shift_deg - prev_deg) > 5) ++jumps;
    prev_deg = f.yaw_c * kRadToDeg - shift_deg;
  }
  EXPECT_GT(jumps, 0);
  // With the margin, the same sweep stays in the basin in use.
  for (int k = 0; k <= 100; ++k) {
    const double shift_deg = 0.01 * k;
    const auto f = fit_well(double_well(1.0 + shift_deg, 0.0002), -3.75 + shift_deg, margin);
    ASSERT_NEAR(f.yaw_c * kRadToDeg, -3.75 + shift_deg, 0.3) << k;
  }
}

TEST(HingeCalibration, ClearlyBetterMinimumWins) {
  // Once the data favour the other basin by more than the margin (here ~5 % lower), the offset
  // moves there, whichever basin is in use; and back when the data turn.
  const double margin = kBasinMargin;
  // Both basins exist (with every minimum a candidate, the one in use is kept) ...
  EXPECT_LT(fit_well(double_well(1.0, 0.15), -3.75, 1.0).yaw_c * kRadToDeg, -2.0);
  EXPECT_GT(fit_well(double_well(1.0, -0.15), 5.75, 1.0).yaw_c * kRadToDeg, 4.0);
  // ... but the lower one by 5 % wins.
  const auto to_far = fit_well(double_well(1.0, 0.15), -3.75, margin);
  EXPECT_GT(to_far.yaw_c * kRadToDeg, 4.0);  // the tilt also moves the minimum (7.2)
  const auto back = fit_well(double_well(1.0, -0.15), 5.75, margin);
  EXPECT_LT(back.yaw_c * kRadToDeg, -2.0);
  // A single minimum is found from any reference.
  DoubleWell one = double_well(1.0, 0);
  one.g.tail<2>() *= 2;  // B = 8 d cos 10 > 4 d: the bump is gone, one minimum at y0
  EXPECT_NEAR(fit_well(one, 30.0, margin).yaw_c * kRadToDeg, 1.0, 1e-6);
}

}  // namespace
}  // namespace mocap

namespace mocap {
namespace {

// Knee segments for the noise-weighting test: `walk` = stepping on the spot with the thighs
// swinging out sideways too (the yaw is well pinned); `turn` = a turn on the spot at 60 deg/s
// with steps, during which the thigh's filter heading runs 3 % ahead of the turn (a gyro
// z-scale error, or a magnetometer heading correction during the turn) and the shank's 2 %
// behind: rates inconsistent with a rigid hinge on the large common rate about the vertical.
struct KneeSample {
  Eigen::Quaterniond thigh, shank;
};
KneeSample knee_motion(double t, double t_turn) {
  const double w = 2 * M_PI * 0.9;
  Eigen::Quaterniond pelvis = Eigen::Quaterniond::Identity();
  double eps_thigh = 0, eps_shank = 0;
  double hip = 0, abd = 0, knee = 0;
  if (t < t_turn) {
    hip = -0.4 * std::sin(w * t);
    abd = 0.15 * std::sin(0.7 * t);
    knee = 0.6 * (1 - std::cos(w * t));
  } else {
    const double yaw = (t - t_turn) * 60 * kDegToRad;
    pelvis = yaw_rotation(yaw);
    eps_thigh = 0.03 * yaw;
    eps_shank = -0.02 * yaw;
    const double lift = std::pow(std::max(0.0, std::sin(w * (t - t_turn))), 2);
    hip = -0.45 * lift;
    knee = 0.8 * lift;
  }
  const Eigen::Quaterniond thigh = pelvis * axis_rotation(1, hip) * axis_rotation(0, abd);
  return {yaw_rotation(eps_thigh) * thigh,
          yaw_rotation(eps_shank) * thigh * axis_rotation(1, knee)};
}

// Identified yaw offsets (deg) of thigh_l and shank_l whose base frames are yawed by
// beta_thigh, beta_shank: 4 s of stepping, then 10 s of turning with inconsistent rates.
std::pair<double, double> knee_yaws_after_turn(bool noise_weighting, double beta_thigh_deg,
                                               double beta_shank_deg) {
  HingeRefineOptions opt;
  opt.noise_weighting = noise_weighting;
  HingeAxisRefiner r(RigMapping::full(), opt);
  std::array<Eigen::Quaterniond, kSegmentCount> q;
  q.fill(Eigen::Quaterniond::Identity());
  std::array<int64_t, kSegmentCount> t_ns{};
  std::array<bool, kSegmentCount> have{};
  have[index(Segment::thigh_l)] = have[index(Segment::shank_l)] = true;
  for (int k = 0; k <= 1400; ++k) {
    const int64_t t = k * 10 * kMs;
    const KneeSample m = knee_motion(t * 1e-9, 4.0);
    q[index(Segment::thigh_l)] = m.thigh * yaw_rotation(-beta_thigh_deg * kDegToRad);
    q[index(Segment::shank_l)] = m.shank * yaw_rotation(-beta_shank_deg * kDegToRad);
    t_ns.fill(t);
    r.add(q, t_ns, have, t);
    r.update(t);
  }
  EXPECT_TRUE(r.hinges()[0].valid && r.hinges()[0].parent_valid);
  return {r.hinges()[0].parent_yaw_deg, r.hinges()[0].child_yaw_deg};
}

TEST(HingeCalibration, NoiseWeightingKeepsCleanFlexionAgainstAnInconsistentTurn) {
  // The turn's rates are inconsistent with the hinge by far more than the stepping's, yet carry
  // large residuals on the big common rate: unweighted, they pull both yaws by degrees (as on
  // the accuracy bench's turn, seed 4: thigh and shank moved 6 and 9 deg). Weighted by each
  // block's own residual level, the clean stepping decides.
  const double beta_t = 4.0, beta_s = -3.0;
  const auto [p_w, c_w] = knee_yaws_after_turn(true, beta_t, beta_s);
  const auto [p_u, c_u] = knee_yaws_after_turn(false, beta_t, beta_s);
  RecordProperty("weighted_error_deg", std::to_string(std::hypot(p_w - beta_t, c_w - beta_s)));
  RecordProperty("unweighted_error_deg", std::to_string(std::hypot(p_u - beta_t, c_u - beta_s)));
  EXPECT_NEAR(p_w, beta_t, 0.3);
  EXPECT_NEAR(c_w, beta_s, 0.3);
  // The scenario is one where it matters: without the weighting the turn wins.
  EXPECT_GT(std::hypot(p_u - beta_t, c_u - beta_s), 1.0);
}

}  // namespace
}  // namespace mocap
