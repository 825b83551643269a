// The parts of `mocap setup` that need no device: which sensor moved alone (MotionJudge), the
// rig text (rig_writer) as mocapd's configuration reader takes it, the ports named on the
// command line (port_candidate).
#include <gtest/gtest.h>

#include <vector>

#include "mocap/daemon/config.hpp"
#include "mocap/setup/candidates.hpp"
#include "mocap/setup/motion_judge.hpp"
#include "mocap/setup/rig_writer.hpp"

using namespace mocap;
using namespace mocap::setup;
using Verdict = MotionJudge::Verdict;

TEST(MotionJudge, AssignsTheSensorThatMovesAloneForTheHoldWindows) {
  MotionJudge j({.threshold_rad_s = 1.0, .dominance = 3.0, .hold_windows = 3});
  const std::vector<bool> free(4, true);
  EXPECT_EQ(j.judge({0.01, 0.02, 0.0, 0.05}, free), Verdict::waiting);  // all at rest
  EXPECT_EQ(j.judge({0.01, 4.0, 0.5, 0.05}, free), Verdict::waiting);   // the forearm shakes
  EXPECT_EQ(j.judge({0.01, 4.0, 0.9, 0.05}, free), Verdict::waiting);
  EXPECT_EQ(j.judge({0.01, 4.0, 0.2, 0.05}, free), Verdict::assigned);
  EXPECT_EQ(j.winner(), 1);
}

TEST(MotionJudge, AStreakIsBrokenByAWindowAtRestOrAnotherSensor) {
  MotionJudge j({.threshold_rad_s = 1.0, .dominance = 3.0, .hold_windows = 2});
  const std::vector<bool> free(3, true);
  EXPECT_EQ(j.judge({3.0, 0.0, 0.0}, free), Verdict::waiting);
  EXPECT_EQ(j.judge({0.1, 0.0, 0.0}, free), Verdict::waiting);
  EXPECT_EQ(j.judge({0.0, 0.0, 3.0}, free), Verdict::waiting);
  EXPECT_EQ(j.judge({3.0, 0.0, 0.0}, free), Verdict::waiting);
  EXPECT_EQ(j.judge({3.0, 0.0, 0.0}, free), Verdict::assigned);
  EXPECT_EQ(j.winner(), 0);
}

TEST(MotionJudge, TwoMovingAtOnceIsAmbiguousAndNamesBoth) {
  MotionJudge j(
      {.threshold_rad_s = 1.0, .dominance = 3.0, .hold_windows = 2, .ambiguous_windows = 2});
  const std::vector<bool> free(3, true);
  EXPECT_EQ(j.judge({0.0, 3.0, 2.0}, free), Verdict::waiting);
  EXPECT_EQ(j.judge({0.0, 3.0, 2.5}, free), Verdict::ambiguous);
  EXPECT_EQ(j.winner(), 1);
  EXPECT_EQ(j.second(), 2);
  EXPECT_FALSE(j.still({0.0, 3.0, 2.5}, free));
  EXPECT_TRUE(j.still({0.2, 0.3, 0.1}, free));
}

TEST(MotionJudge, AssignedSensorsAreNotCandidates) {
  // An elbow bends: forearm (1) and hand (2) turn alike; the hand already has its segment.
  MotionJudge j({.threshold_rad_s = 1.0, .dominance = 3.0, .hold_windows = 2});
  const std::vector<bool> free = {true, true, false};
  EXPECT_EQ(j.judge({0.0, 3.0, 3.0}, free), Verdict::waiting);
  EXPECT_EQ(j.judge({0.0, 3.0, 3.1}, free), Verdict::assigned);
  EXPECT_EQ(j.winner(), 1);
  EXPECT_TRUE(j.still({0.0, 0.0, 9.0}, free));
}

TEST(RigWriter, WritesARigMocapdAccepts) {
  RigPlan plan;
  daemon::SensorConfig a;
  a.name = a.segment = "pelvis";
  a.driver = "witmotion";
  a.port = "/dev/ttyUSB0";
  a.baud = 115200;
  a.rate_hz = 100;
  daemon::SensorConfig b;
  b.name = b.segment = "thigh_l";
  b.driver = "slimevr";
  b.port = "udp:0.0.0.0:6969";
  b.options = {{"mac", "02:5E:00:00:00:03"}, {"tracker", "1"}};
  daemon::SensorConfig c;
  c.name = c.segment = "hand_r";
  c.driver = "ds4";
  c.vid = 0x054c;
  c.pid = 0x09cc;
  c.hid = true;
  c.serial = "ab:cd";
  plan.sensors = {a, b, c};
  plan.left_out = {"SlimeVR tracker 02:5E:00:00:00:09"};
  plan.no_sensor = {"neck"};
  plan.silent = {"serial port /dev/ttyUSB7"};
  plan.use_mag = false;
  plan.calibration_file = "rig-calibration.toml";
  const std::string text = rig_toml(plan);
  daemon::ConfigErrors errors;
  const auto cfg = daemon::parse_config(text, "rig", {}, errors, &daemon::default_validators());
  ASSERT_TRUE(cfg) << errors.to_string() << text;
  ASSERT_EQ(cfg->sensors.size(), 3u);
  EXPECT_EQ(cfg->sensors[0].port, "/dev/ttyUSB0");
  EXPECT_EQ(cfg->sensors[0].baud, 115200);
  EXPECT_EQ(cfg->sensors[0].rate_hz, 100);
  EXPECT_EQ(cfg->sensors[1].options.at("mac"), "02:5E:00:00:00:03");
  EXPECT_EQ(cfg->sensors[1].options.at("tracker"), "1");
  EXPECT_EQ(cfg->sensors[2].vid, 0x054c);
  EXPECT_EQ(cfg->sensors[2].serial, "ab:cd");
  EXPECT_TRUE(cfg->sensors[2].hid);
  EXPECT_FALSE(cfg->filter.use_mag);
  EXPECT_EQ(cfg->calibration.file, "rig-calibration.toml");
  EXPECT_NE(text.find("# heard but never moved alone, left out: SlimeVR tracker 02:5E:00:00:00:09"),
            std::string::npos);
  EXPECT_NE(text.find("# no sensor moved for segment neck"), std::string::npos);
  EXPECT_NE(text.find("# found but sent nothing: serial port /dev/ttyUSB7"), std::string::npos);
}

TEST(SetupCandidates, APortIsProbedUnlessItsDriverIsNamed) {
  const Candidate generic = port_candidate("/dev/ttyUSB3");
  ASSERT_EQ(generic.probes.size(), 3u);
  EXPECT_EQ(generic.sensor.driver, "witmotion");
  EXPECT_EQ(generic.sensor.baud, 115200);
  EXPECT_EQ(generic.probes.back().driver, "line");
  const Candidate named = port_candidate("/dev/rfcomm0@line");
  ASSERT_EQ(named.probes.size(), 1u);
  EXPECT_EQ(named.sensor.port, "/dev/rfcomm0");
  EXPECT_EQ(named.sensor.driver, "line");
  EXPECT_THROW(port_candidate("/dev/ttyUSB0@nonsense"), std::invalid_argument);
}
