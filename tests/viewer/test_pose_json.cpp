// Pose JSON lines: a valid line gives the frame; every malformed variant is rejected with a
// message and leaves the previous frame untouched; random corruption never yields NaN.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "mocap/viewer/avatar_geometry.hpp"
#include "mocap/viewer/pose_json.hpp"

namespace mocap::viewer {
namespace {

std::string valid_line(double x = 0.5) {
  std::string s = "{\"v\":1,\"frame\":42,\"t\":12.5,\"flags\":5,\"segments\":[";
  for (int i = 0; i < kSegmentCount; ++i) {
    if (i) s += ",";
    s += "{\"name\":\"" + std::string(kSegmentNames[i]) + "\",\"q\":[0.70711,0,0,0.70711],\"p\":[" +
         std::to_string(x) + ",-1.25," + std::to_string(0.1 * i) +
         "],\"flags\":" + (i == 11 ? "17" : "1") + "}";
  }
  s += "],\"joints\":[{\"name\":\"shank_l\",\"q\":[1,0,0,0],\"violation_deg\":7.5}],"
       "\"sensors\":[{\"name\":\"imu0\",\"segment\":\"pelvis\",\"state\":2,\"rate_hz\":100.0,"
       "\"age_ms\":3.2,\"drops\":4,\"errors\":0,\"flags\":64},"
       "{\"name\":\"imu1\",\"segment\":null,\"state\":3,\"rate_hz\":0,\"age_ms\":900,"
       "\"drops\":0,\"errors\":1,\"flags\":0}]}";
  return s;
}

TEST(PoseJson, ParsesTheStreamSchema) {
  PoseFrame f;
  std::string err;
  ASSERT_TRUE(parse_pose_json(valid_line() + "\n", f, err)) << err;
  EXPECT_EQ(f.frame, 42u);
  EXPECT_EQ(f.t_ns, 12500000000);
  EXPECT_EQ(f.flags, kFrameCalibrated | kFrameRecording);
  EXPECT_NEAR(f.q_earth_segment[3][3], 0.70711f, 1e-5);
  EXPECT_FLOAT_EQ(f.p_earth_segment_m[4][1], -1.25f);
  EXPECT_FLOAT_EQ(f.p_earth_segment_m[4][2], 0.4f);
  EXPECT_EQ(f.segment_flags[11], kSegTracked | kSegLimitViolated);
  EXPECT_FLOAT_EQ(f.joint_violation_deg[11], 7.5f);
  ASSERT_EQ(f.sensor_count, 2u);
  EXPECT_STREQ(f.sensors[0].name, "imu0");
  EXPECT_EQ(f.sensors[0].segment, 0);
  EXPECT_EQ(f.sensors[0].flags, kSegAtRest);
  EXPECT_EQ(f.sensors[0].drops, 4u);
  EXPECT_EQ(f.sensors[1].segment, -1);
  EXPECT_EQ(f.sensors[1].state, 3);
  EXPECT_TRUE(pose_is_finite(f));
}

TEST(PoseJson, RejectsMalformedLinesWithAReason) {
  const std::string good = valid_line();
  auto replace = [&](const std::string& from, const std::string& to) {
    std::string s = good;
    const auto at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return s.replace(at, from.size(), to);
  };
  const std::pair<std::string, std::string> cases[] = {
      {"", "not a JSON object"},
      {"[1,2,3]", "not a JSON object"},
      {good.substr(0, good.size() / 2), "not a JSON object"},
      {replace("\"v\":1", "\"v\":2"), "version 2"},
      {replace("\"v\":1,", ""), "version"},
      {replace("\"frame\":42", "\"frame\":-1"), "frame"},
      {replace("[0.70711,0,0,0.70711]", "[null,0,0,1]"), "quaternion"},
      {replace("[0.70711,0,0,0.70711]", "[0,0,0,0]"), "quaternion"},
      {replace("[0.70711,0,0,0.70711]", "[1,0,0]"), "quaternion"},
      {replace("-1.25", "null"), "position"},
      {replace("-1.25", "\"x\""), "position"},
      {replace("\"name\":\"pelvis\"", "\"name\":\"hips\""), "named pelvis"},
      {replace("\"t\":12.5", "\"t\":\"soon\""), "\"t\""},
  };
  PoseFrame f;
  reset_pose(f);
  f.frame = 99;
  for (const auto& [line, reason] : cases) {
    std::string err;
    EXPECT_FALSE(parse_pose_json(line, f, err)) << line;
    EXPECT_NE(err.find(reason), std::string::npos) << "error '" << err << "' for " << line;
    EXPECT_EQ(f.frame, 99u) << "a rejected line leaves the frame alone";
  }
  std::string err;
  EXPECT_FALSE(parse_pose_json(std::string(kMaxPoseJsonLine + 1, ' '), f, err));
}

TEST(PoseJson, CorruptedLinesNeverGiveANonFinitePose) {
  // Deterministic corruption: flipped, deleted and inserted bytes.
  std::mt19937 rng(1234);
  const std::string good = valid_line(1.0);
  const std::string alphabet = "0123456789-+.eE,:[]{}\"nul ";
  int accepted = 0;
  for (int k = 0; k < 3000; ++k) {
    std::string s = good;
    const int edits = 1 + static_cast<int>(rng() % 4);
    for (int e = 0; e < edits; ++e) {
      const size_t at = rng() % s.size();
      switch (rng() % 3) {
        case 0:
          s[at] = alphabet[rng() % alphabet.size()];
          break;
        case 1:
          s.erase(at, 1);
          break;
        default:
          s.insert(at, 1, alphabet[rng() % alphabet.size()]);
      }
    }
    PoseFrame f;
    std::string err;
    if (parse_pose_json(s, f, err)) {
      ++accepted;
      ASSERT_TRUE(pose_is_finite(f)) << s;
    } else {
      ASSERT_FALSE(err.empty());
    }
  }
  EXPECT_GT(accepted, 0) << "some corruptions hit only ignorable fields";
}

}  // namespace
}  // namespace mocap::viewer
