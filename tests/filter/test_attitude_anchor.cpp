// AttitudeFilter::anchor_heading() and the residual hard-iron path: an offset present from
// power-on is unknown while the sensor stands still (a calibration pose) and learnt once it
// rotates; the anchored output keeps the heading error it had at the anchor (the one a
// calibration absorbed), the plain output loses it; a walking thigh with a 1.7 uT residual
// keeps its calibration heading (docs/filter.md steps 10-11).
#include <gtest/gtest.h>

#include "mocap/filter/attitude_filter.hpp"
#include "synth.hpp"

namespace mocap::test {
namespace {

// Still for 10 s (the calibration pose), then hand-like rotation about all axes.
SynthConfig still_then_rotating(double duration_s) {
  SynthConfig c;
  c.q0 = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()));
  c.duration_s = duration_s;
  c.gyr_true = [](double t) -> Eigen::Vector3d {
    if (t < 10) return Eigen::Vector3d::Zero();
    const double ramp = std::min((t - 10) / 2, 1.0);
    return ramp * Eigen::Vector3d(1.5 * std::sin(1.1 * t), 1.2 * std::sin(0.7 * t + 1),
                                  1.0 * std::sin(0.5 * t + 2));
  };
  return c;
}

/// Heading error of q_est against the truth (rotation about earth z), degrees.
double heading_error_deg(const Eigen::Quaterniond& q_est, const Eigen::Quaterniond& q_true) {
  const Eigen::Quaterniond e = (q_est * q_true.conjugate()).normalized();
  return 2.0 * std::atan2(e.z(), e.w()) / kDeg;
}

struct AnchorRun {
  double at_anchor_deg = 0;       ///< heading error when anchored (what a calibration absorbs)
  double max_change_deg = 0;      ///< largest |error - that| from t_from_s on
  double anchor_heading_deg = 0;  ///< the anchor's correction at the end
  Eigen::Vector3d offset_uT = Eigen::Vector3d::Zero();
};

AnchorRun run(const SynthStream& s, bool anchor, double t_anchor_s, double t_from_s,
              const FilterParams& p = {}) {
  AttitudeFilter f(p);
  AnchorRun r;
  bool anchored = false;
  for (size_t i = 0; i < s.samples.size(); ++i) {
    f.update(s.samples[i]);
    EXPECT_TRUE(f.q_earth_sensor().coeffs().allFinite());
    const double t = s.samples[i].t_host_ns * 1e-9;
    const double e = heading_error_deg(f.q_earth_sensor(), s.truth[i]);
    if (!anchored && t >= t_anchor_s) {
      anchored = true;
      if (anchor) f.anchor_heading();
      r.at_anchor_deg = e;
    }
    if (t >= t_from_s)
      r.max_change_deg =
          std::max(r.max_change_deg, std::abs(std::remainder(e - r.at_anchor_deg, 360.0)));
  }
  r.anchor_heading_deg = f.anchor_heading_rad() / kDeg;
  r.offset_uT = f.hard_iron_uT();
  return r;
}

TEST(AttitudeAnchor, OffsetLearntAfterTheAnchorKeepsTheAnchoredHeadingError) {
  auto s = make_stream(still_then_rotating(90));
  const Eigen::Vector3d h(2.5, -2, 1.5);  // 3.5 uT from power-on (field 20 uT horizontal)
  for (auto& smp : s.samples)
    if (smp.valid & kFieldMag) smp.mag_uT += h;
  const AnchorRun plain = run(s, false, 8, 50);
  const AnchorRun anchored = run(s, true, 8, 50);
  // Nothing learnt while still: the anchor pose carries the offset's heading error.
  EXPECT_GT(std::abs(plain.at_anchor_deg), 5.0);
  EXPECT_NEAR(plain.at_anchor_deg, anchored.at_anchor_deg, 1e-9);
  // Learnt during the rotation (so the plain output's error leaves the anchored value) ...
  EXPECT_LT((anchored.offset_uT - h).norm(), 1.5);
  EXPECT_GT(plain.max_change_deg, 5.0);
  // ... the anchored output keeps it: correction ~ the anchor pose's error, change small.
  EXPECT_NEAR(anchored.anchor_heading_deg, anchored.at_anchor_deg, 2.0);
  EXPECT_LT(anchored.max_change_deg, 3.0);
}

// A thigh while walking: still 8 s (the N-pose), then flexion +-35 deg at 0.9 Hz about the
// sensor's y axis with turns (+-0.4 rad/s about its z axis, 20 s period).
SynthConfig walking_thigh(double duration_s) {
  SynthConfig c;
  c.q0 = Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()));
  c.duration_s = duration_s;
  c.gyr_true = [](double t) -> Eigen::Vector3d {
    if (t < 8) return Eigen::Vector3d::Zero();
    const double ramp = std::min((t - 8) / 2, 1.0);
    const double w = 2 * kPi * 0.9;
    return ramp * Eigen::Vector3d(0.05 * std::sin(2 * w * t), 0.61 * w * std::cos(w * t),
                                  0.4 * std::sin(2 * kPi * t / 20));
  };
  return c;
}

TEST(AttitudeAnchor, WalkingThighWithAResidualKeepsItsCalibrationHeading) {
  // A 1.7 uT residual (what a factory calibration leaves; 1 uT per axis in the sensor model)
  // on a walking, turning thigh: the heading error changes with the orientation unless the
  // residual is learnt, and learning it turns the calibration unless it is anchored.
  auto s = make_stream(walking_thigh(120));
  const Eigen::Vector3d h(1.0, -1.0, 0.9);
  for (auto& smp : s.samples)
    if (smp.valid & kFieldMag) smp.mag_uT += h;
  FilterParams former;  // before: residuals never applied (no norm/dip deviation to explain)
  former.hard_iron_consistent_nis = 0;
  const AnchorRun before = run(s, true, 6, 60, former);
  const AnchorRun after = run(s, true, 6, 60);
  // Measured: before 5.0 deg of change, after 1.85 with 0.7 uT of the offset still unlearnt
  // (the estimate's 1-sigma ramp shrinks it).
  EXPECT_LT((after.offset_uT - h).norm(), 1.0);
  EXPECT_LT(after.max_change_deg, 0.5 * before.max_change_deg);
  EXPECT_LT(after.max_change_deg, 2.5);
}

TEST(AttitudeAnchor, NoOffsetNoCorrectionAndClearRestoresThePlainOutput) {
  const auto s = make_stream(still_then_rotating(60));
  const AnchorRun anchored = run(s, true, 8, 20);
  EXPECT_LT(std::abs(anchored.anchor_heading_deg), 0.5);
  EXPECT_LT(anchored.max_change_deg, 2.0);
  AttitudeFilter f;
  for (const auto& smp : s.samples)
    f.update(smp);
  f.anchor_heading();
  f.clear_heading_anchor();
  EXPECT_EQ(f.anchor_heading_rad(), 0.0);
  EXPECT_TRUE(f.q_earth_sensor().isApprox(f.state().q_delta * f.q_earth_sensor_6d()));
}

}  // namespace
}  // namespace mocap::test
