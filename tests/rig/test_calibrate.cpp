// The calibration from a still-pose capture (pose_capture.hpp, calibrate.hpp, alignment.hpp):
// mounting rotations recovered for arbitrary mountings, the body-heading sources, quality
// refusal, never a refusal for want of standard sites, the heading reset; when a measured facing
// replaces an assumed one (facing.hpp).
#include <gtest/gtest.h>

#include <optional>

#include "../skeleton/skeleton_test_util.hpp"
#include "mocap/rig/calibrate.hpp"
#include "mocap/rig/facing.hpp"

namespace mocap::rig {
namespace {

using test::kMs;

/// A capture and its calibration, as the body tracker runs them (an arm_swing N-pose kept for
/// the T-pose after it).
struct Cal {
  PoseCapturer capturer;
  CalibrationSetup setup;
  Alignment alignment;
  std::optional<PoseCapture> npose;
  explicit Cal(RigMapping rig, CalibrationSetup s = {}) : capturer(rig), setup(s) {}
  void start(CalibrationPose pose, int64_t t0) { capturer.start(pose, t0); }
  void add_sample(int s, const Eigen::Quaterniond& q, int64_t t,
                  const Eigen::Vector3d* acc = nullptr) {
    capturer.add_sample(s, q, t, acc);
  }
  bool done(int64_t t) const { return capturer.done(t); }
  CalibrationResult finish() {
    const PoseCapturer::Result c = capturer.finish();
    const bool tpose = c.capture.pose == CalibrationPose::tpose;
    CalibrationResult r = calibrate(c, setup, {}, tpose && npose ? &*npose : nullptr, alignment);
    if (r.status == CalibrationStatus::need_tpose) npose = c.capture;
    return r;
  }
};

CalibrationSetup pelvis_axis() {
  CalibrationSetup s;
  s.heading = HeadingSource::pelvis_sensor;
  return s;
}

struct MountedRig {
  std::array<Eigen::Quaterniond, kSegmentCount> q_sensor_segment;  // true mounting
  std::array<Eigen::Quaterniond, kSegmentCount> q_drift;           // per-sensor earth yaw error
  explicit MountedRig(std::mt19937& rng) {
    for (auto& q : q_sensor_segment)
      q = test::random_rotation(rng);
    q_drift.fill(Eigen::Quaterniond::Identity());
  }
  Eigen::Quaterniond sensor(int s, const Eigen::Quaterniond& q_earth_segment) const {
    return (q_drift[s] * q_earth_segment * q_sensor_segment[s].conjugate()).normalized();
  }
};

// Feeds a still pose (with optional jitter) for 2 s at 50 Hz.
void capture(Cal& cal, const MountedRig& rig, CalibrationPose pose, double heading_rad,
             std::mt19937& rng, double jitter_deg, int64_t t0, bool with_acc = false,
             double acc_tilt_deg = 0) {
  cal.start(pose, t0);
  const Eigen::Quaterniond body = yaw_rotation(heading_rad);
  for (int k = 0; k <= 100; ++k) {
    const int64_t t = t0 + k * 20 * kMs;
    for (int s = 0; s < kSegmentCount; ++s) {
      const Eigen::Quaterniond seg =
          body * q_body_segment_in_pose(pose, s) * test::random_small_rotation(rng, jitter_deg);
      const Eigen::Quaterniond qs = rig.sensor(s, seg);
      // Specific force: +g up in the earth frame, seen in the sensor frame (optionally tilted).
      const Eigen::Vector3d f_earth =
          Eigen::AngleAxisd(acc_tilt_deg * kRadPerDeg, Eigen::Vector3d::UnitX()) *
          Eigen::Vector3d(0, 0, 9.80665);
      const Eigen::Vector3d acc = qs.conjugate() * f_earth;
      cal.add_sample(s, qs, t, with_acc ? &acc : nullptr);
    }
  }
  EXPECT_TRUE(cal.done(t0 + 2000 * kMs));
}

double worst_segment_error_deg(const Calibration& c, const MountedRig& rig, std::mt19937& rng) {
  double worst = 0;
  for (int trial = 0; trial < 20; ++trial) {
    const auto pose = test::random_pose(rng, 60);
    for (int s = 0; s < kSegmentCount; ++s)
      worst = std::max(
          worst, angle_between_deg(c.segment_from_sensor(s, rig.sensor(s, pose[s])), pose[s]));
  }
  return worst;
}

TEST(Calibration, NPoseRecoversArbitraryMountingsWithExplicitHeading) {
  std::mt19937 rng(1);
  MountedRig rig(rng);
  CalibrationSetup o;
  o.heading = HeadingSource::explicit_heading;
  o.explicit_heading_deg = 37;
  Cal cal(RigMapping::full(), o);
  capture(cal, rig, CalibrationPose::npose, 37 * kRadPerDeg, rng, 0, 0);
  const auto r = cal.finish();
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_NEAR(r.calibration.heading_deg, 37, 1e-9);
  EXPECT_LT(worst_segment_error_deg(r.calibration, rig, rng), 1e-6);
}

TEST(Calibration, TPoseRecoversMountingsWithPelvisHeading) {
  std::mt19937 rng(2);
  MountedRig rig(rng);
  rig.q_sensor_segment[0] = yaw_rotation(0);   // pelvis sensor: x forward (the source's premise)
  Cal cal(RigMapping::full(), pelvis_axis());  // heading from the pelvis sensor
  capture(cal, rig, CalibrationPose::tpose, -120 * kRadPerDeg, rng, 0, 0);
  const auto r = cal.finish();
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_NEAR(r.calibration.heading_deg, -120, 1e-6);
  EXPECT_LT(worst_segment_error_deg(r.calibration, rig, rng), 1e-6);
}

TEST(Calibration, ArmSwingFindsHeadingWithEverySensorMountedArbitrarily) {
  std::mt19937 rng(3);
  MountedRig rig(rng);
  CalibrationSetup o;
  o.heading = HeadingSource::arm_swing;
  Cal cal(RigMapping::full(), o);
  const double heading = 71 * kRadPerDeg;
  capture(cal, rig, CalibrationPose::npose, heading, rng, 0.3, 0);
  auto r = cal.finish();
  EXPECT_EQ(r.status, CalibrationStatus::need_tpose) << r.message;
  capture(cal, rig, CalibrationPose::tpose, heading, rng, 0.3, 5000 * kMs);
  r = cal.finish();
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_NEAR(r.calibration.heading_deg, 71, 0.5);
  // Still-pose jitter of 0.3 deg leaves sub-degree mounting errors.
  EXPECT_LT(worst_segment_error_deg(r.calibration, rig, rng), 1.0);
  EXPECT_LT(r.calibration.motion_deg, 0.5);
}

TEST(Calibration, MountNormalsAverageOutEachSensorsMisalignment) {
  // Each sensor's z lies along its site's outward normal (any strap roll about it), turned by a
  // misalignment of +-4 deg about the vertical; the pelvis alone would be 4 deg off. One sensor's
  // filter took a local field as north (25 deg): left out of the mean.
  std::mt19937 rng(3);
  MountedRig rig(rng);
  CalibrationSetup o;
  o.heading = HeadingSource::mount_normals;
  std::uniform_real_distribution<double> roll(-M_PI, M_PI);
  int used = 0;
  for (int s = 0; s < kSegmentCount; ++s) {
    const double az = 0.4 * s;  // a different horizontal normal per site
    const Eigen::Vector3d n(std::cos(az), std::sin(az), s == index(Segment::head) ? 5.0 : 0.0);
    o.site_normal_body[s] = n;
    const double mis_deg = (s % 2 ? 4.0 : -4.0) * (s == 0 ? -1 : 1);
    const Eigen::Quaterniond q_segment_sensor =
        yaw_rotation(mis_deg * kRadPerDeg) *
        Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), n) *
        Eigen::Quaterniond(Eigen::AngleAxisd(roll(rng), Eigen::Vector3d::UnitZ()));
    rig.q_sensor_segment[s] = q_segment_sensor.conjugate();
    if (s != index(Segment::head)) ++used;
  }
  ASSERT_EQ(used % 2, 1);  // odd: the +-4 deg leave a residual of 4/used deg at most
  rig.q_drift[index(Segment::hand_r)] = yaw_rotation(25 * kRadPerDeg);
  Cal cal(RigMapping::full(), o);
  capture(cal, rig, CalibrationPose::npose, 20 * kRadPerDeg, rng, 0, 0);
  const auto r = cal.finish();
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_NEAR(r.calibration.heading_deg, 20, 0.6);
  EXPECT_EQ(r.calibration.heading_source, HeadingSource::mount_normals);

  // The sensor whose filter took the local field for north is reported, and the others not.
  EXPECT_NE(r.heading_off_normal_rad[index(Segment::hand_r)], 0);
  EXPECT_NE(r.message.find("hand_r"), std::string::npos) << r.message;

  // No site with a known horizontal normal: not refused; the body heading is reported as not
  // determined, and every mounting is still right up to that one heading.
  CalibrationSetup none = o;
  none.site_normal_body.fill(Eigen::Vector3d::Zero());
  Cal cal2(RigMapping::full(), none);
  capture(cal2, rig, CalibrationPose::npose, 20 * kRadPerDeg, rng, 0, 0);
  const auto r2 = cal2.finish();
  ASSERT_TRUE(r2.ok()) << r2.message;
  EXPECT_FALSE(r2.body_heading_known);
  EXPECT_NE(r2.message.find("body heading not determined"), std::string::npos) << r2.message;
}

TEST(Calibration, WrongHeadingSourceGivesWrongMountings) {
  // Guard for the test above: with an arbitrarily mounted pelvis sensor, the pelvis heading is
  // wrong and so are the mountings (the error the arm-swing source removes).
  std::mt19937 rng(3);
  MountedRig rig(rng);
  Cal cal(RigMapping::full(), pelvis_axis());
  capture(cal, rig, CalibrationPose::npose, 0.4, rng, 0, 0);
  const auto r = cal.finish();
  if (r.ok()) {
    EXPECT_GT(worst_segment_error_deg(r.calibration, rig, rng), 5.0);
  }
}

TEST(Calibration, RefusesMotionAndInconsistentGravity) {
  std::mt19937 rng(4);
  MountedRig rig(rng);
  {
    Cal cal(RigMapping::full());
    capture(cal, rig, CalibrationPose::npose, 0, rng, 8.0, 0);
    const auto r = cal.finish();
    EXPECT_EQ(r.status, CalibrationStatus::refused);
    EXPECT_NE(r.message.find("moved"), std::string::npos) << r.message;
    // ... and says what to do differently.
    EXPECT_NE(r.message.find("Stand still for the whole capture"), std::string::npos) << r.message;
  }
  {
    Cal cal(RigMapping::full());
    capture(cal, rig, CalibrationPose::npose, 0, rng, 0, 0, true, 12.0);
    const auto r = cal.finish();
    EXPECT_EQ(r.status, CalibrationStatus::refused);
    EXPECT_NE(r.message.find("gravity"), std::string::npos) << r.message;
    EXPECT_NEAR(r.gravity_error_deg[5], 12.0, 0.01);
    EXPECT_NE(r.message.find("lie still for a few seconds"), std::string::npos) << r.message;
  }
  {
    rig.q_sensor_segment[0] = Eigen::Quaterniond::Identity();
    Cal cal(RigMapping::full());
    capture(cal, rig, CalibrationPose::npose, 0, rng, 0, 0, true, 1.0);
    const auto r = cal.finish();
    EXPECT_NE(r.status, CalibrationStatus::refused) << r.message;
  }
  {
    // A sensor that never reports.
    RigMapping m = RigMapping::full();
    Cal cal(m);
    cal.start(CalibrationPose::npose, 0);
    for (int k = 0; k < 100; ++k)
      cal.add_sample(0, Eigen::Quaterniond::Identity(), k * 20 * kMs);
    const auto r = cal.finish();
    EXPECT_EQ(r.status, CalibrationStatus::refused);
    EXPECT_NE(r.message.find("torso: only 0 samples"), std::string::npos) << r.message;
    EXPECT_NE(r.message.find("every sensor streams"), std::string::npos) << r.message;
  }
}

TEST(Calibration, HeadingResetRemovesPerSensorYawDrift) {
  std::mt19937 rng(5);
  MountedRig rig(rng);
  CalibrationSetup o;
  o.heading = HeadingSource::explicit_heading;
  Cal cal(RigMapping::full(), o);
  capture(cal, rig, CalibrationPose::npose, 0, rng, 0, 0);
  auto r = cal.finish();
  ASSERT_TRUE(r.ok());
  Calibration c = r.calibration;
  // Each sensor's heading drifts differently.
  std::uniform_real_distribution<double> d(-30, 30);
  for (auto& q : rig.q_drift)
    q = yaw_rotation(d(rng) * kRadPerDeg);
  const double drifted = worst_segment_error_deg(c, rig, rng);
  EXPECT_GT(drifted, 10);
  // Reset while standing in N-pose facing 25 deg.
  std::array<Eigen::Quaterniond, kSegmentCount> now;
  std::array<bool, kSegmentCount> have;
  const Eigen::Quaterniond body = yaw_rotation(25 * kRadPerDeg);
  for (int s = 0; s < kSegmentCount; ++s) {
    now[s] = rig.sensor(s, body);
    have[s] = true;
  }
  Alignment a;
  a.load(c);
  a.reset_heading(now, have);
  c = a.calibration();
  for (int s = 0; s < kSegmentCount; ++s)
    EXPECT_EQ(a.segment(s).heading_source, AlignSource::heading_reset);
  // Everything shares the pelvis's (drifted) heading now: joint rotations are right again.
  for (int trial = 0; trial < 10; ++trial) {
    const auto pose = test::random_pose(rng, 60);
    std::array<Eigen::Quaterniond, kSegmentCount> est;
    for (int s = 0; s < kSegmentCount; ++s)
      est[s] = c.segment_from_sensor(s, rig.sensor(s, pose[s]));
    for (int s = 1; s < kSegmentCount; ++s) {
      const int p = kSegmentParent[s];
      EXPECT_LT(angle_between_deg(est[p].conjugate() * est[s], pose[p].conjugate() * pose[s]),
                1e-6);
    }
  }
}

// A measured facing (a hinge axis, the mounting motion) contradicts an assumed one (a site
// normal, a sensor axis) only beyond three combined sigmas; nothing contradicts a measured one.
TEST(Facing, AMeasuredFacingContradictsAnAssumedOneOnlyBeyondThreeSigmas) {
  const auto facing = [](double yaw_deg, double sigma_deg, AlignSource source) {
    return Facing{yaw_deg * kRadPerDeg, sigma_deg, source};
  };
  const Facing site = facing(170, 8, AlignSource::site_normal);
  // 3 x hypot(8, 7) = 31.9 deg, across the +-180 wrap.
  EXPECT_FALSE(contradicts(site, facing(-160, 7, AlignSource::hinge_axis)));  // 30 deg apart
  EXPECT_TRUE(contradicts(site, facing(-155, 7, AlignSource::hinge_axis)));   // 35 deg
  EXPECT_TRUE(contradicts(site, facing(120, 7, AlignSource::motion)));
  EXPECT_FALSE(contradicts(site, facing(120, 20, AlignSource::hinge_axis)));  // unsure: 64.5
  EXPECT_FALSE(
      contradicts(facing(170, 8, AlignSource::motion), facing(100, 7, AlignSource::hinge_axis)));
  EXPECT_FALSE(contradicts(site, facing(100, 7, AlignSource::site_normal)));
  EXPECT_FALSE(contradicts(Facing{}, facing(100, 7, AlignSource::hinge_axis)));
  // replaces() takes a contradicting one, and an agreeing one only when surer.
  EXPECT_TRUE(replaces(site, facing(120, 9, AlignSource::hinge_axis)));
  EXPECT_FALSE(replaces(site, facing(165, 9, AlignSource::hinge_axis)));
  EXPECT_TRUE(replaces(site, facing(165, 5, AlignSource::hinge_axis)));
}

}  // namespace
}  // namespace mocap::rig
