// BROAD CSV reader: good files (plain and gzip), rate from the comment or the t column, and
// line-precise errors for malformed input.
#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "mocap/core/units.hpp"
#include "mocap/eval/broad_csv.hpp"
#include "mocap/eval/broad_metric.hpp"

namespace mocap {
namespace {

const char* kGood =
    "# BROAD trial 99_test, 100.000000 Hz, CC BY 4.0\n"
    "t,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z,mag_x,mag_y,mag_z,ref_w,ref_x,ref_y,ref_z,movement\n"
    "0.00,0.1,0.2,0.3,0,0,9.81,1,2,3,1,0,0,0,0\n"
    "0.01,0.1,0.2,0.3,0,0,9.81,1,2,3,nan,nan,nan,nan,1\n"
    "0.02,0.1,0.2,0.3,0,0,9.81,1,2,3,1,0,0,0,1\n";

TEST(BroadCsv, ParsesGoodText) {
  BroadTrial t;
  std::string err;
  ASSERT_TRUE(parse_broad_csv(kGood, t, err)) << err;
  EXPECT_EQ(t.name, "99_test");
  EXPECT_DOUBLE_EQ(t.rate_hz, 100.0);
  ASSERT_EQ(t.size(), 3u);
  EXPECT_TRUE(t.has_mag && t.has_ref && t.has_movement);
  EXPECT_DOUBLE_EQ(t.gyr_rad_s[1].z(), 0.3);
  EXPECT_TRUE(std::isnan(t.ref_wxyz[1][0]));
  EXPECT_EQ(t.movement[1], 1);
}

TEST(BroadCsv, RateFromTimeColumnAndOptionalColumns) {
  BroadTrial t;
  std::string err;
  ASSERT_TRUE(
      parse_broad_csv("acc_x,acc_y,acc_z,t,gyr_x,gyr_y,gyr_z\n"
                      "0,0,9.8,0.0,0,0,0\n0,0,9.8,0.02,0,0,0\n0,0,9.8,0.04,0,0,0\n",
                      t, err))
      << err;
  EXPECT_NEAR(t.rate_hz, 50.0, 1e-9);
  EXPECT_FALSE(t.has_mag);
  EXPECT_DOUBLE_EQ(t.acc_m_s2[2].z(), 9.8);
}

struct BadCase {
  const char* text;
  const char* expect;  // substring of the error
};

TEST(BroadCsv, MalformedInputNamesLineAndProblem) {
  const BadCase cases[] = {
      {"", "no header"},
      {"# only a comment\n", "no header"},
      {"t,gyr_x,gyr_y,acc_x,acc_y,acc_z\n", "line 1: header lacks required column 'gyr_z'"},
      {"t,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z\n0,0,0,0,0,0,9.8\n0.1,0,0,x1,0,0,9.8\n",
       "line 3: column 4 ('gyr_z'): not a number: 'x1'"},
      {"t,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z\n0,0,0,0,0,0\n",
       "line 2: expected 7 fields, found 6"},
      {"t,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z\n0.1,0,0,0,0,0,9.8\n0.1,0,0,0,0,0,9.8\n",
       "line 3: time 't' does not increase"},
      {"t,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z\n", "no samples"},
      {"t,t,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z\n", "repeated"},
  };
  for (const auto& c : cases) {
    BroadTrial t;
    std::string err;
    EXPECT_FALSE(parse_broad_csv(c.text, t, err)) << c.text;
    EXPECT_NE(err.find(c.expect), std::string::npos) << "got: " << err;
  }
}

TEST(BroadCsv, ReadsGzipAndPlainFiles) {
  const auto dir = std::filesystem::temp_directory_path() / "mocap_test_broad_csv";
  std::filesystem::create_directories(dir);
  const std::string plain = (dir / "a.csv").string(), gz = (dir / "b.csv.gz").string();
  { std::ofstream(plain) << kGood; }
  gzFile f = gzopen(gz.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  gzputs(f, kGood);
  gzclose(f);
  for (const auto& p : {plain, gz}) {
    BroadTrial t;
    std::string err;
    ASSERT_TRUE(read_broad_csv(p, t, err)) << err;
    EXPECT_EQ(t.size(), 3u);
  }
  EXPECT_EQ(list_broad_trials(dir.string()).size(), 2u);
  BroadTrial t;
  std::string err;
  EXPECT_FALSE(read_broad_csv((dir / "missing.csv").string(), t, err));
  EXPECT_NE(err.find("cannot open"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(BroadMetric, SplitsHeadingAndInclination) {
  const Eigen::Quaterniond ref(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()));
  double t, h, i;
  // A pure rotation about earth z of 5 deg is all heading.
  attitude_error_angles(
      Eigen::Quaterniond(Eigen::AngleAxisd(5 * kRadPerDeg, Eigen::Vector3d::UnitZ())) * ref, ref, t,
      h, i);
  EXPECT_NEAR(t * kDegPerRad, 5.0, 1e-9);
  EXPECT_NEAR(h * kDegPerRad, 5.0, 1e-9);
  EXPECT_NEAR(i, 0.0, 1e-7);
  attitude_error_angles(
      Eigen::Quaterniond(Eigen::AngleAxisd(3 * kRadPerDeg, Eigen::Vector3d::UnitX())) * ref, ref, t,
      h, i);
  EXPECT_NEAR(i * kDegPerRad, 3.0, 1e-9);
  EXPECT_NEAR(h, 0.0, 1e-9);
  // score_trial only counts movement samples with a finite reference.
  BroadTrial tr;
  std::string err;
  ASSERT_TRUE(parse_broad_csv(kGood, tr, err));
  std::vector<Eigen::Quaterniond> est(
      3, Eigen::Quaterniond(Eigen::AngleAxisd(2 * kRadPerDeg, Eigen::Vector3d::UnitZ())));
  est[0] = Eigen::Quaterniond(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitX()));  // not moving
  const AttitudeErrors e = score_trial(tr, est);
  EXPECT_EQ(e.n, 1u);
  EXPECT_NEAR(e.heading_deg, 2.0, 1e-9);
}

}  // namespace
}  // namespace mocap
