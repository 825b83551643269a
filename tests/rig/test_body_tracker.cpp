// BodyTracker: the invariant that no body-level correction changes a segment's motion (each is
// its own sensor's filter output through the calibration), 6D calibration without refusal and
// its alignment from motion turning no faster than a heading drifts, orientation sources (the
// sensor's own orientation in place of the filter).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <optional>
#include <string>

#include "mocap/rig/body_tracker.hpp"
#include "mocap/skeleton/joint_limits.hpp"

namespace mocap::rig {
namespace {

// Three sensors flat on their standard sites, each in a frame turned about the vertical by its
// own angle (as 6D filters start), standing still in the N-pose for 3 s, then turning.
struct Rig {
  std::vector<TrackerSensor> sensors;
  std::vector<Eigen::Quaterniond> q_earth_sensor0;  // in the N-pose
  Rig() {
    for (Segment s : {Segment::pelvis, Segment::thigh_l, Segment::foot_l}) {
      TrackerSensor t;
      t.segment = index(s);
      sensors.push_back(t);
    }
    // Sensor z along each site's outward normal (pelvis: -x, thigh_l: front-left, foot: up).
    q_earth_sensor0 = {
        Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), -Eigen::Vector3d::UnitX()),
        Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(),
                                           Eigen::Vector3d(1, 0.4, 0).normalized()),
        Eigen::Quaterniond::Identity()};
  }
};

ImuSample sample(int id, const Eigen::Quaterniond& q_earth_sensor, const Eigen::Vector3d& w,
                 int64_t t_ns, bool mag) {
  ImuSample s;
  s.sensor_id = static_cast<uint16_t>(id);
  s.t_host_ns = t_ns;
  s.valid = kFieldGyr | kFieldAcc | (mag ? kFieldMag : 0);
  s.gyr_rad_s = w;
  s.acc_m_s2 = q_earth_sensor.conjugate() * Eigen::Vector3d(0, 0, 9.81);
  s.mag_uT = q_earth_sensor.conjugate() * Eigen::Vector3d(0, 25, -43);
  return s;
}

/// A tracker of the test rig calibrating from the mount normals over a 1 s capture.
BodyTracker mount_normals_tracker(const Rig& rig, bool use_mag) {
  TrackerOptions o;
  o.use_mag = use_mag;
  o.calibration.heading = HeadingSource::mount_normals;
  o.capture.capture_s = 1.0;
  return BodyTracker(BodyModel{}, default_joint_limits(), rig.sensors, o);
}

void run(bool use_mag, const std::function<void(BodyTracker&, const PoseFrame&)>& check) {
  Rig rig;
  BodyTracker tracker = mount_normals_tracker(rig, use_mag);
  tracker.start_calibration(CalibrationPose::npose, 1'500'000'000);
  const Eigen::Vector3d w_earth(0.2, 0.5, 1.0);  // the whole body turning after 3 s
  PoseFrame frame;
  for (int k = 0; k < 600; ++k) {
    const int64_t t = static_cast<int64_t>(k) * 10'000'000;
    const double turn_s = std::max(0.0, k * 0.01 - 3.0);
    const Eigen::Quaterniond r(Eigen::AngleAxisd(turn_s * w_earth.norm(), w_earth.normalized()));
    for (int i = 0; i < 3; ++i) {
      const Eigen::Quaterniond q = r * rig.q_earth_sensor0[i];
      const Eigen::Vector3d w =
          k * 0.01 > 3.0 ? Eigen::Vector3d(q.conjugate() * w_earth) : Eigen::Vector3d::Zero();
      tracker.on_sample(i, sample(i, q, w, t, use_mag));
    }
    if (auto res = tracker.take_calibration_result()) {
      ASSERT_TRUE(res->ok()) << res->message;
    }
    tracker.solve(t, frame);
    check(tracker, frame);
  }
  EXPECT_TRUE(tracker.skeleton().calibration().valid);
}

TEST(BodyTracker, EachSegmentIsItsSensorsFilterThroughTheCalibration) {
  for (bool use_mag : {true, false}) {
    int checked = 0;
    run(use_mag, [&](BodyTracker& t, const PoseFrame&) {
      const Calibration& c = t.skeleton().calibration();
      if (!c.valid) return;
      for (int i = 0; i < t.sensor_count(); ++i) {
        const int seg = t.sensor(i).segment;
        const Eigen::Quaterniond want = c.segment_from_sensor(seg, t.q_earth_sensor(i));
        EXPECT_LT(t.skeleton().q_earth_segment()[seg].angularDistance(want), 1e-12) << seg;
      }
      ++checked;
    });
    EXPECT_GT(checked, 300) << use_mag;
  }
}

// 6D: once a segment's alignment from motion is found, later evidence turns it no faster than
// a 6D heading drifts (max_drift_deg_s; a fit still settling may turn at settle_turn_deg_s,
// which none here does after its first turn), whatever the motion says, and evidence that would
// turn it over (here the whole body turning rigidly tells the thigh's fit 176 deg) is refused and
// reported: no segment flips.
TEST(BodyTracker, SixDAlignmentTurnsNoFasterThanTheDriftLimitAndNeverFlips) {
  const double max_deg_s = HeadingFromMotionOptions{}.max_drift_deg_s;
  std::array<std::optional<Eigen::Quaterniond>, kSegmentCount> last;
  std::array<int64_t, kSegmentCount> last_t{};
  std::array<int, kSegmentCount> turns{};
  std::optional<Eigen::Quaterniond> thigh0;
  double thigh_turned_deg = 0;
  uint32_t rejected = 0;
  int64_t t_ns = 0;
  run(false, [&](BodyTracker& t, const PoseFrame& f) {
    t_ns = f.t_ns;
    const Calibration& c = t.skeleton().calibration();
    if (!c.valid) return;
    const int thigh = index(Segment::thigh_l);
    if (!thigh0) thigh0 = c.q_correction[thigh];
    thigh_turned_deg =
        std::max(thigh_turned_deg, c.q_correction[thigh].angularDistance(*thigh0) / kRadPerDeg);
    rejected = t.alignment().segment(thigh).rejected_turns;
    for (int i = 0; i < t.sensor_count(); ++i) {
      const int seg = t.sensor(i).segment;
      const Eigen::Quaterniond q = c.q_correction[seg];
      if (last[seg] && q.angularDistance(*last[seg]) > 1e-9) {
        if (++turns[seg] > 1) {  // the first turn aligns; later ones follow the drift limit
          const double dt_s = static_cast<double>(t_ns - last_t[seg]) * 1e-9;
          EXPECT_LE(q.angularDistance(*last[seg]) / kRadPerDeg, max_deg_s * dt_s + 1e-6)
              << kSegmentNames[seg] << " at " << t_ns * 1e-9 << " s";
        }
        last_t[seg] = t_ns;
      } else if (!last[seg]) {
        last_t[seg] = t_ns;
      }
      last[seg] = q;
    }
  });
  // The thigh's refinement saw evidence for a turn over: refused, counted, the thigh kept.
  EXPECT_GT(rejected, 10u);
  EXPECT_LT(thigh_turned_deg, 1.0);
}

void six_d_calibration(bool rig_use_mag) {
  Rig rig;
  BodyTracker tracker = mount_normals_tracker(rig, rig_use_mag);
  tracker.start_calibration(CalibrationPose::npose, 500'000'000);
  std::optional<CalibrationResult> res;
  for (int k = 0; k < 200 && !res; ++k)
    for (int i = 0; i < 3; ++i) {
      tracker.on_sample(i, sample(i, rig.q_earth_sensor0[i], Eigen::Vector3d::Zero(),
                                  static_cast<int64_t>(k) * 10'000'000, false));
      if (!res) res = tracker.take_calibration_result();
    }
  ASSERT_TRUE(res && res->ok()) << (res ? res->message : "no result");
  EXPECT_TRUE(res->facing[index(Segment::pelvis)].known());
  EXPECT_TRUE(res->facing[index(Segment::thigh_l)].known());
  EXPECT_FALSE(res->facing[index(Segment::foot_l)].known());  // vertical normal
  EXPECT_NE(res->message.find("foot_l"), std::string::npos) << res->message;
  EXPECT_TRUE(tracker.heading_from_motion().active());
}

// A 6D sensor silent for over heading_lost_after_s (a radio drop, a tracker rebooting) comes
// back with its heading marked lost (counted), a shorter gap does not unless its device says it
// restarted (kFlagDeviceRestarted: a tracker that rebooted quickly), a 9D sensor never (its
// magnetometer brings its heading back); a heading reset answers it. A sensor fused on its
// device (SlimeVR over UDP: its orientation ran on through the silence) loses it only at a
// restart.
TEST(BodyTracker, ASixDHeadingLostInADropoutIsMarkedAndAHeadingResetAnswersIt) {
  struct Case {
    double gap_s;
    bool restarted, fused;
  };
  for (const bool use_mag : {false, true})
    for (const auto [gap_s, restarted, fused] :
         {Case{0.5, false, false}, Case{1.5, false, false}, Case{0.5, true, false},
          Case{1.5, false, true}, Case{1.5, true, true}}) {
      Rig rig;
      rig.sensors[1].fused_on_device = fused;
      BodyTracker tracker = mount_normals_tracker(rig, use_mag);
      tracker.start_calibration(CalibrationPose::npose, 1'500'000'000);
      const int thigh = index(Segment::thigh_l);
      bool lost_seen = false;
      for (int k = 0; k < 500; ++k) {
        const int64_t t = static_cast<int64_t>(k) * 10'000'000;
        for (int i = 0; i < 3; ++i) {
          if (i == 1 && k * 0.01 >= 3.0 && k * 0.01 < 3.0 + gap_s) continue;  // thigh silent
          ImuSample s = sample(i, rig.q_earth_sensor0[i], Eigen::Vector3d::Zero(), t, use_mag);
          if (i == 1 && restarted && k == static_cast<int>(std::lround((3.0 + gap_s) * 100)))
            s.flags |= kFlagDeviceRestarted;
          tracker.on_sample(i, s);
        }
        if (auto res = tracker.take_calibration_result()) {
          ASSERT_TRUE(res->ok()) << res->message;
        }
        lost_seen = lost_seen || tracker.alignment().segment(thigh).heading_lost;
      }
      const bool expect_lost = !use_mag && ((gap_s > 1.0 && !fused) || restarted);
      const std::string what = std::string(use_mag ? "9D" : "6D") + " gap " +
                               std::to_string(gap_s) + (restarted ? " restarted" : "") +
                               (fused ? " fused on the device" : "");
      EXPECT_EQ(lost_seen, expect_lost) << what;
      EXPECT_EQ(tracker.alignment().segment(thigh).lost_headings, expect_lost ? 1u : 0u) << what;
      // Standing still, nothing finds it from motion: still lost, until a heading reset.
      EXPECT_EQ(tracker.alignment().segment(thigh).heading_lost, expect_lost) << what;
      tracker.reset_heading();
      EXPECT_FALSE(tracker.alignment().segment(thigh).heading_lost) << what;
      EXPECT_EQ(tracker.alignment().segment(thigh).lost_headings, expect_lost ? 1u : 0u) << what;
    }
}

TEST(BodyTracker, SixDCalibratesWithoutAMagnetometerAndMarksTheBorrowedHeadings) {
  six_d_calibration(false);
}

// A 9D rig whose sensors send no magnetometer samples (a 6D device in a default config):
// calibrated as 6D, never refused.
TEST(BodyTracker, SensorsWithoutMagnetometerSamplesAreTakenAsSixD) {
  six_d_calibration(true);
}

// Orientation sources (SlimeVR trackers: the orientation computed on the tracker, no rates):
// the tracker uses the sent orientation as is (its filter never runs), calibrates them like 6D
// sensors, and each segment is that orientation through the calibration.
TEST(BodyTracker, OrientationSourcesSkipTheFilterAndCalibrate) {
  Rig rig;
  TrackerOptions o;
  o.calibration.heading = HeadingSource::mount_normals;
  o.capture.capture_s = 1.0;
  BodyTracker tracker(BodyModel{}, default_joint_limits(), rig.sensors, o);
  tracker.start_calibration(CalibrationPose::npose, 500'000'000);
  std::optional<CalibrationResult> res;
  const Eigen::Vector3d w_earth(0.3, -0.2, 0.8);
  PoseFrame frame;
  int checked = 0;
  for (int k = 0; k < 400; ++k) {
    const int64_t t = static_cast<int64_t>(k) * 10'000'000;
    const double turn_s = std::max(0.0, k * 0.01 - 2.0);
    const Eigen::Quaterniond r(Eigen::AngleAxisd(turn_s * w_earth.norm(), w_earth.normalized()));
    for (int i = 0; i < 3; ++i) {
      ImuSample s;
      s.sensor_id = static_cast<uint16_t>(i);
      s.t_host_ns = t;
      s.q_device_sensor = r * rig.q_earth_sensor0[i];
      s.acc_m_s2 = s.q_device_sensor.conjugate() * Eigen::Vector3d(0, 0, 9.81);
      s.valid = kFieldQuat | kFieldAcc;
      tracker.on_sample(i, s);
      EXPECT_TRUE(tracker.orientation_source(i));
      EXPECT_LT(tracker.q_earth_sensor(i).angularDistance(s.q_device_sensor), 1e-12);
      if (!res) res = tracker.take_calibration_result();
    }
    tracker.solve(t, frame);
    const Calibration& c = tracker.skeleton().calibration();
    if (!c.valid) continue;
    for (int i = 0; i < 3; ++i) {
      const int seg = tracker.sensor(i).segment;
      const Eigen::Quaterniond want = c.segment_from_sensor(seg, tracker.q_earth_sensor(i));
      EXPECT_LT(tracker.skeleton().q_earth_segment()[seg].angularDistance(want), 1e-12);
    }
    ++checked;
  }
  ASSERT_TRUE(res && res->ok()) << (res ? res->message : "no result");
  EXPECT_GT(checked, 200);
  for (int i = 0; i < 3; ++i)
    EXPECT_EQ(tracker.filter(i).counters().gyr_ok, 0u) << "the filter never ran";
}

}  // namespace
}  // namespace mocap::rig
