// Calibration: the saved form (text and file round trip, parse errors). Computing one is the
// body tracker's (tests/rig/test_calibrate.cpp).
#include <gtest/gtest.h>

#include "mocap/skeleton/calibration.hpp"
#include "skeleton_test_util.hpp"

namespace mocap {
namespace {

TEST(Calibration, SerialisesAndParsesExactly) {
  std::mt19937 rng(6);
  Calibration c;
  c.valid = true;
  c.pose = CalibrationPose::tpose;
  c.heading_source = HeadingSource::arm_swing;
  c.heading_deg = 12.345678901234567;
  c.motion_deg = 0.25;
  for (int s = 0; s < kSegmentCount; s += 2) {
    c.calibrated[s] = true;
    c.q_sensor_segment[s] = test::random_rotation(rng);
    c.q_correction[s] = yaw_rotation(0.1 * s);
  }
  const std::string text = serialize_calibration(c);
  const Calibration back = parse_calibration(text);
  EXPECT_EQ(back.valid, c.valid);
  EXPECT_EQ(back.pose, c.pose);
  EXPECT_EQ(back.heading_source, c.heading_source);
  EXPECT_EQ(back.heading_deg, c.heading_deg);
  for (int s = 0; s < kSegmentCount; ++s) {
    EXPECT_EQ(back.calibrated[s], c.calibrated[s]);
    if (!c.calibrated[s]) continue;
    EXPECT_EQ(back.q_sensor_segment[s].coeffs(), c.q_sensor_segment[s].coeffs());
    EXPECT_EQ(back.q_correction[s].coeffs(), c.q_correction[s].coeffs());
  }
  // File round trip.
  const std::string path = std::string(MOCAP_BINARY_DIR) + "/test_calibration.toml";
  save_calibration(c, path);
  EXPECT_EQ(serialize_calibration(load_calibration(path)), text);
}

TEST(Calibration, ParseErrorsNameTheProblemAndPlace) {
  auto err = [](std::string_view text) {
    try {
      parse_calibration(text, "cal.toml");
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(err("[calibration]\nversion = 1\n[segment.elbow]\nq_sensor_segment=[1,0,0,0]\n")
                .find("cal.toml:3:"),
            std::string::npos);
  EXPECT_NE(err("[calibration]\nversion = 1\n[segment.elbow]\n").find("unknown segment 'elbow'"),
            std::string::npos);
  EXPECT_NE(err("[calibration]\nversion = 1\n[segment.head]\nq_sensor_segment=[2,0,0,0]\n")
                .find("not a unit quaternion"),
            std::string::npos);
  EXPECT_NE(err("[calibration]\nversion = 2\n").find("version"), std::string::npos);
  EXPECT_NE(err("[calibration\n").find("cal.toml:1:"), std::string::npos);
  EXPECT_NE(err("").find("missing [calibration]"), std::string::npos);
}

}  // namespace
}  // namespace mocap
