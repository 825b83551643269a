// The daemon's calibration file holds the calibration in use: the N-pose capture first, then the
// same calibration refined from knee/elbow motion (HingeAxisRefiner), so a restart (and a
// recording, which stores the file's content) gets the refined one back. The virtual performer
// stands in the N-pose and walks; its samples go through the real RigEngine.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "mocap/core/units.hpp"
#include "mocap/daemon/config.hpp"
#include "mocap/daemon/rig_engine.hpp"
#include "mocap/sim/body_pose.hpp"
#include "mocap/sim/motion.hpp"
#include "mocap/sim/performer.hpp"
#include "mocap/sim/sensor_model.hpp"
#include "mocap/sim/table_spin.hpp"
#include "mocap/skeleton/calibration.hpp"
#include "mocap/skeleton/sensor_sites.hpp"

namespace mocap::daemon {
namespace {

namespace fs = std::filesystem;

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

double max_quat_diff(const Calibration& a, const Calibration& b) {
  double d = std::abs(a.heading_deg - b.heading_deg) * 1e-3;
  for (int i = 0; i < kSegmentCount; ++i) {
    if (a.calibrated[i] != b.calibrated[i]) return 1.0;
    d = std::max(d, (a.q_sensor_segment[i].coeffs() - b.q_sensor_segment[i].coeffs()).norm());
    d = std::max(d, (a.q_correction[i].coeffs() - b.q_correction[i].coeffs()).norm());
  }
  return d;
}

// The performer's sensors, one per segment; with `site_turn_deg`, each with its standard
// site's normal turned by that much about the vertical as an explicit site_normal.
std::vector<SensorConfig> performer_sensors(std::optional<double> site_turn_deg = {}) {
  std::vector<SensorConfig> out;
  for (int i = 0; i < sim::Performer::kSensorCount; ++i) {
    SensorConfig s;
    s.name = std::string(sim::Performer::sensor_name(i));
    s.segment = s.name;
    s.driver = "direct";
    if (site_turn_deg) {
      const Eigen::Vector3d n =
          Eigen::AngleAxisd(*site_turn_deg * kRadPerDeg, Eigen::Vector3d::UnitZ()) *
          standard_site_normal_body(*segment_from_name(s.segment));
      s.site_normal = std::array<double, 3>{n.x(), n.y(), n.z()};
    }
    out.push_back(s);
  }
  return out;
}

// Feeds the performer's samples into `engine` at 100 Hz until end_s, starts the N-pose
// capture at capture_at_s, and calls after_frame(t_ns, frame) after each frame.
template <typename AfterFrame>
void drive(RigEngine& engine, sim::Performer& perf, double end_s, double capture_at_s,
           AfterFrame after_frame) {
  PoseFrame frame;
  std::vector<ImuSample> samples;
  bool capture_started = false;
  for (int k = 1; k * 0.01 <= end_s; ++k) {
    const int64_t t_ns = static_cast<int64_t>(k) * 10'000'000;
    samples.clear();
    perf.step_to(t_ns, samples);
    for (const ImuSample& s : samples)
      engine.on_sample(s.sensor_id, s);
    if (!capture_started && k * 0.01 >= capture_at_s) {
      engine.calibrate(CalibrationPose::npose, false);
      capture_started = true;
    }
    engine.build_frame(t_ns, frame);
    after_frame(t_ns, frame);
  }
}

TEST(DaemonCalibrationFile, CalibrationIsSavedAndReloaded) {
  const fs::path file =
      fs::temp_directory_path() / ("mocap-refined-calib-" + std::to_string(getpid()) + ".toml");
  fs::remove(file);
  ConfigErrors errs;
  std::optional<Config> parsed = parse_config("", "<defaults>", {}, errs);
  ASSERT_TRUE(parsed) << errs.to_string();
  Config cfg = *parsed;
  cfg.calibration.file = file.string();
  const Eigen::Vector3d axis = sim::pelvis_forward_axis_sensor();
  cfg.calibration.heading_axis_sensor = {axis.x(), axis.y(), axis.z()};
  cfg.sensors = performer_sensors();
  sim::PerformerParams pp;
  pp.motion = "walk";
  pp.loop = false;
  sim::Performer perf(pp);
  const auto [calib_begin_s, calib_end_s] = perf.calibration_window_s();
  const double capture_at_s = calib_end_s - 0.3 - cfg.calibration.capture_s;
  ASSERT_GT(capture_at_s, calib_begin_s + 0.5);

  RigEngine engine(cfg);
  PoseFrame frame;
  std::string npose_text;
  const double end_s = perf.track().period_s();
  drive(engine, perf, end_s, capture_at_s, [&](int64_t, const PoseFrame&) {
    engine.flush_calibration_file();  // written by a thread: wait for it before looking
    if (npose_text.empty() && fs::exists(file)) npose_text = read_text(file);
  });
  ASSERT_FALSE(npose_text.empty()) << engine.last_calibration_message();
  // The status reports the capture's outcome, with how far the performer stood from the pose.
  const CalibrationProgress progress = engine.calibration_progress();
  const std::string message = progress.message.data();
  EXPECT_EQ(message.rfind("calibrated in npose", 0), 0u) << message;
  EXPECT_NE(message.find("furthest from the npose"), std::string::npos) << message;
  // The walk after it leaves the calibration as captured (the solve never changes it), and the
  // file holds it.
  const Calibration saved = load_calibration(file.string());
  EXPECT_EQ(parse_calibration(npose_text).heading_deg, saved.heading_deg);
  EXPECT_LT(max_quat_diff(saved, engine.skeleton().calibration()), 1e-12);
  // A restart loads it.
  RigEngine restarted(cfg);
  EXPECT_LT(max_quat_diff(restarted.skeleton().calibration(), saved), 1e-12);
  fs::remove(file);
}

// The N-pose calibration of the performer's stand through the real RigEngine.
Calibration npose_calibration(const Config& cfg) {
  sim::PerformerParams pp;
  pp.motion = "walk";
  pp.loop = false;
  sim::Performer perf(pp);
  const double calib_end_s = perf.calibration_window_s().second;
  const double capture_at_s = calib_end_s - 0.3 - cfg.calibration.capture_s;
  RigEngine engine(cfg);
  drive(engine, perf, calib_end_s, capture_at_s, [](int64_t, const PoseFrame&) {});
  return engine.skeleton().calibration();
}

TEST(DaemonCalibrationHeading, MountNormalsByDefaultAndSiteNormalsFromTheConfig) {
  // The performer faces +x (body heading 0) with its sensors flat on the standard sites.
  ConfigErrors errs;
  std::optional<Config> parsed = parse_config("", "<defaults>", {}, errs);
  ASSERT_TRUE(parsed) << errs.to_string();
  Config cfg = *parsed;
  cfg.sensors = performer_sensors();
  const Calibration normals = npose_calibration(cfg);
  ASSERT_TRUE(normals.valid);
  EXPECT_EQ(normals.heading_source, HeadingSource::mount_normals);
  // The sensors' mount misalignments average over the sites: measured -3.5 deg (the pelvis
  // belt clip alone: -5.3; seeds 1..5 of the accuracy bench: |normals| <= 3.5, |pelvis| <= 5.7).
  EXPECT_LT(std::abs(normals.heading_deg), 5.0);
  // Every site's normal given in the config, turned by 20 deg about the vertical: the body
  // heading read from them turns by -20 deg (the sensors are where they were).
  cfg.sensors = performer_sensors(20.0);
  const Calibration turned = npose_calibration(cfg);
  ASSERT_TRUE(turned.valid);
  EXPECT_NEAR(turned.heading_deg, normals.heading_deg - 20, 0.5);
  // The pelvis belt clip as the heading source: recorded as such.
  cfg.sensors = performer_sensors();
  cfg.calibration.heading = HeadingSource::pelvis_sensor;
  const Eigen::Vector3d axis = sim::pelvis_forward_axis_sensor();
  cfg.calibration.heading_axis_sensor = {axis.x(), axis.y(), axis.z()};
  const Calibration pelvis = npose_calibration(cfg);
  ASSERT_TRUE(pelvis.valid);
  EXPECT_EQ(pelvis.heading_source, HeadingSource::pelvis_sensor);
  EXPECT_GT(std::abs(pelvis.heading_deg - normals.heading_deg), 0.1);
}

// RMS error (deg) of one joint (the rotation of `joint` relative to its parent) after the
// calibration procedure of `motion`, through the real RigEngine with the default config and the
// performer's sensors; `setup` adjusts the config before the engine is built, `check` looks at
// the engine once built.
template <typename Setup, typename Check>
double joint_rmse_deg(const char* motion, uint64_t seed, Segment joint, Setup setup, Check check) {
  ConfigErrors errs;
  std::optional<Config> parsed = parse_config("", "<defaults>", {}, errs);
  EXPECT_TRUE(parsed) << errs.to_string();
  Config cfg = *parsed;
  cfg.sensors = performer_sensors();
  sim::PerformerParams pp;
  pp.motion = std::string("calibrate+") + motion;
  pp.seed = seed;
  pp.loop = false;
  sim::Performer perf(pp);
  setup(cfg, perf);
  const double calib_end_s = perf.calibration_window_s().second;
  const double eval_from_s = calib_end_s + sim::calibration_moves_s();
  RigEngine engine(cfg);
  check(engine);
  const int j = index(joint);
  double sum_sq = 0;
  int n = 0;
  sim::TruthFrame truth;
  drive(engine, perf, perf.track().period_s(), calib_end_s - 0.3 - cfg.calibration.capture_s,
        [&](int64_t t_ns, const PoseFrame&) {
          const double t_s = t_ns * 1e-9;
          if (t_s < eval_from_s) return;
          perf.truth_at(t_s, truth);
          const double e =
              engine.skeleton().q_parent_segment()[j].angularDistance(truth.q_parent_segment[j]);
          sum_sq += e * e;
          ++n;
        });
  EXPECT_GT(n, 500);
  return n ? std::sqrt(sum_sq / n) / kRadPerDeg : 1e9;
}

// Each sensor's gyr_scale from its one-time table-spin calibration (estimate_gyro_scale on
// the virtual sensor's spins) reaches the filters and the skeleton: the left hip after the turn
// motion's 180 deg turns (seed 2, the closest cell of the accuracy grid), where the gyros' scale
// errors turn the thigh's and the pelvis's headings apart.
TEST(DaemonGyroScale, TableSpinCalibrationKeepsTheHipThroughTurns) {
  const auto hip = [](bool calibrated) {
    return joint_rmse_deg(
        "turn", 2, Segment::thigh_l,
        [&](Config& cfg, sim::Performer& perf) {
          if (!calibrated) return;
          for (int i = 0; i < sim::Performer::kSensorCount; ++i) {
            const Eigen::Vector3d g = sim::calibrated_gyro_scale(perf.sensor_errors(i), 100);
            cfg.sensors[i].gyr_scale = std::array<double, 3>{g.x(), g.y(), g.z()};
          }
        },
        [&](RigEngine& engine) {
          // Every sensor's scale reaches the tracker.
          for (int i = 0; i < sim::Performer::kSensorCount; ++i)
            EXPECT_EQ(engine.tracker().sensor(i).gyr_scale != Eigen::Vector3d::Ones(), calibrated)
                << i;
        });
  };
  const double on = hip(true), off = hip(false);
  std::printf("hip_l RMSE with/without the gyro scale calibration: %.2f / %.2f deg\n", on, off);
  EXPECT_LT(on, off - 0.5);
  EXPECT_LT(on, 2.5);
}

}  // namespace
}  // namespace mocap::daemon

namespace mocap::daemon {
namespace {

// The configured body reaches the pose: a forearm override sets the elbow-to-wrist distance of
// the streamed positions, and a tightened left-knee limit flags (never clamps) the squat's left
// knee while the right knee, under the default limit, stays inside it.
TEST(DaemonBody, ConfiguredSegmentsAndJointLimitsReachThePose) {
  ConfigErrors errs;
  std::optional<Config> parsed = parse_config(
      "[body.segment.hand_l]\njoint_offset_m = [0, 0, -0.40]\n"
      "[body.joint.knee_l]\nb_deg = [-5, 60]\n",
      "<test>", {}, errs);
  ASSERT_TRUE(parsed) << errs.to_string();
  Config cfg = *parsed;
  cfg.sensors = performer_sensors();
  sim::PerformerParams pp;
  pp.motion = "squat";
  pp.loop = false;
  sim::Performer perf(pp);
  const auto [calib_begin_s, calib_end_s] = perf.calibration_window_s();
  RigEngine engine(cfg);
  int knee_l_flagged = 0, knee_r_flagged = 0, frames = 0;
  double max_forearm_m = 0;
  const int shank_l = index(Segment::shank_l), shank_r = index(Segment::shank_r);
  const int forearm = index(Segment::forearm_l), hand = index(Segment::hand_l);
  drive(engine, perf, perf.track().period_s(), calib_end_s - 0.3 - cfg.calibration.capture_s,
        [&](int64_t, const PoseFrame& frame) {
          if (!(frame.flags & kFrameCalibrated)) return;
          ++frames;
          knee_l_flagged += (frame.segment_flags[shank_l] & kSegLimitViolated) != 0;
          knee_r_flagged += (frame.segment_flags[shank_r] & kSegLimitViolated) != 0;
          const auto& a = frame.p_earth_segment_m[forearm];
          const auto& b = frame.p_earth_segment_m[hand];
          max_forearm_m =
              std::max<double>(max_forearm_m, std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]));
        });
  ASSERT_GT(frames, 300) << engine.last_calibration_message();
  EXPECT_NEAR(max_forearm_m, 0.40, 1e-4);
  EXPECT_GT(knee_l_flagged, 50);  // the squat flexes the knees to 105 deg
  EXPECT_EQ(knee_r_flagged, 0);
  EXPECT_DOUBLE_EQ(engine.skeleton().limits().joint[shank_l].b_max_deg, 60);
}

}  // namespace
}  // namespace mocap::daemon
