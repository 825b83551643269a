// CSV sample importer: columns in any order, optional magnetometer, strict errors with line and
// column, time order.
#include <gtest/gtest.h>

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
