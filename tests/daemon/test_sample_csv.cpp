// CSV sample importer: columns in any order, optional magnetometer, strict errors with line and
// column, time order.
#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <filesystem>
#include <fstream>

#include "mocap/daemon/replay.hpp"
#include "mocap/daemon/sample_csv.hpp"

using mocap::ImuSample;
using mocap::daemon::SampleCsvParser;

TEST(SampleCsv, ParsesRowsAndSensors) {
  SampleCsvParser p("a.csv");
  ImuSample s;
  EXPECT_EQ(p.feed_line("t,sensor,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z,mag_x,mag_y,mag_z\r", s), 0);
  ASSERT_EQ(p.feed_line("0.5,pelvis,0.1,0.2,0.3,0,0,9.81,20,0,-40", s), 1) << p.error();
  EXPECT_EQ(s.t_host_ns, 500'000'000);
  EXPECT_EQ(s.sensor_id, 0);
  EXPECT_TRUE(s.has(mocap::kFieldMag));
  EXPECT_DOUBLE_EQ(s.gyr_rad_s.z(), 0.3);
  EXPECT_DOUBLE_EQ(s.mag_uT.z(), -40);
  EXPECT_EQ(p.feed_line("# comment", s), 0);
  ASSERT_EQ(p.feed_line("0.5, head ,0,0,0,0,0,9.81,,,", s), 1) << p.error();
  EXPECT_EQ(s.sensor_id, 1);
  EXPECT_FALSE(s.has(mocap::kFieldMag));
  ASSERT_EQ(p.sensors().size(), 2u);
  EXPECT_EQ(p.sensors()[1], "head");
}

TEST(SampleCsv, ColumnsInAnyOrderWithoutMag) {
  SampleCsvParser p;
  ImuSample s;
  ASSERT_EQ(p.feed_line("sensor,t,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z", s), 0) << p.error();
  ASSERT_EQ(p.feed_line("foot_l,1.0,1,2,3,4,5,6", s), 1) << p.error();
  EXPECT_DOUBLE_EQ(s.acc_m_s2.x(), 1);
  EXPECT_DOUBLE_EQ(s.gyr_rad_s.z(), 6);
  EXPECT_FALSE(s.has(mocap::kFieldMag));
}

TEST(SampleCsv, ErrorsNameLineAndColumn) {
  ImuSample s;
  {
    SampleCsvParser p("x.csv");
    EXPECT_EQ(p.feed_line("t,sensor,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z,mag_z", s), -1);
    EXPECT_NE(p.error().find("x.csv:1: give all of mag_x"), std::string::npos) << p.error();
  }
  {
    SampleCsvParser p("x.csv");
    EXPECT_EQ(p.feed_line("t,sensor,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z,gyro", s), -1);
    EXPECT_NE(p.error().find("unknown column 'gyro'"), std::string::npos) << p.error();
  }
  SampleCsvParser p("x.csv");
  ASSERT_EQ(p.feed_line("t,sensor,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z", s), 0);
  EXPECT_EQ(p.feed_line("0.1,a,0,0,nan,0,0,9.8", s), -1);
  EXPECT_NE(p.error().find("x.csv:2: column 'gyr_z': 'nan' is not a finite number"),
            std::string::npos)
      << p.error();
  EXPECT_EQ(p.feed_line("0.1,a,0,0,0,0,0", s), -1);
  EXPECT_NE(p.error().find("expected 8 columns, found 7"), std::string::npos) << p.error();
  EXPECT_EQ(p.feed_line("0.2,a,0,0,0,0,0,9.8", s), 1);
  EXPECT_EQ(p.feed_line("0.1,a,0,0,0,0,0,9.8", s), -1);
  EXPECT_NE(p.error().find("backwards"), std::string::npos) << p.error();
  EXPECT_EQ(p.feed_line("0.2,a,0,0,0,0,0,9.8", s), -1);
  EXPECT_NE(p.error().find("same time"), std::string::npos) << p.error();
  EXPECT_EQ(p.feed_line("x,a,0,0,0,0,0,9.8", s), -1);
  EXPECT_NE(p.error().find("column 't'"), std::string::npos) << p.error();
}

// `mocap replay` and mocapd --replay read a sample CSV plain or gzip-compressed (the shared
// recordings are .csv.gz): the same samples either way; a damaged stream is an error naming
// the file, and the samples before it are kept.
TEST(SampleCsv, GzipSourceReadsAsPlain) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("mocap-csvgz-" + std::to_string(getpid()));
  fs::create_directories(dir);
  std::string text = "t,sensor,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z\n";
  for (int i = 0; i < 2000; ++i)
    text += std::to_string(0.01 * i) + (i % 2 ? ",foot_l," : ",pelvis,") + std::to_string(i) +
            ",0,0,0,0,9.81\n";
  const std::string plain = (dir / "s.csv").string(), gz = (dir / "s.csv.gz").string();
  std::ofstream(plain) << text;
  gzFile f = gzopen(gz.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  ASSERT_EQ(gzwrite(f, text.data(), static_cast<unsigned>(text.size())),
            static_cast<int>(text.size()));
  gzclose(f);
  auto read_all = [](const std::string& path, std::string& err) {
    std::vector<ImuSample> v;
    auto src = mocap::daemon::open_sample_source(path, nullptr);
    ImuSample s;
    while (src->next(s))
      v.push_back(s);
    err = src->error();
    EXPECT_EQ(src->config().sensors.size(), 2u);
    return v;
  };
  std::string err;
  const auto a = read_all(plain, err);
  EXPECT_EQ(err, "");
  const auto b = read_all(gz, err);
  EXPECT_EQ(err, "");
  ASSERT_EQ(a.size(), 2000u);
  ASSERT_EQ(b.size(), a.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].t_host_ns, b[i].t_host_ns);
    EXPECT_EQ(a[i].sensor_id, b[i].sensor_id);
    EXPECT_EQ(a[i].gyr_rad_s, b[i].gyr_rad_s);
  }
  // Cut the compressed stream short: the first pass (sensor names) reads to the damage.
  const auto size = fs::file_size(gz);
  fs::resize_file(gz, size / 2);
  std::string what;
  try {
    read_all(gz, err);
  } catch (const std::exception& e) {
    what = e.what();
  }
  if (what.empty()) what = err;
  EXPECT_NE(what.find("s.csv.gz"), std::string::npos) << what;
  fs::remove_all(dir);
}
