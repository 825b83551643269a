// CalibrationSaver: the calibration file is written by a thread, the newest offer wins, the
// destructor writes what is still waiting, and an unwritable path is logged, not thrown.
#include "mocap/daemon/calibration_saver.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <string>

namespace mocap::daemon {
namespace {

namespace fs = std::filesystem;

fs::path temp_path(const std::string& name) {
  return fs::temp_directory_path() / (name + "-" + std::to_string(getpid()) + ".toml");
}

Calibration calibration_with_heading(double heading_deg) {
  Calibration c;
  c.valid = true;
  c.heading_deg = heading_deg;
  c.calibrated[0] = true;
  c.q_sensor_segment[0] = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()));
  return c;
}

TEST(CalibrationSaver, FlushWritesTheNewestOffer) {
  const fs::path file = temp_path("saver-newest");
  fs::remove(file);
  CalibrationSaver saver(file.string(), nullptr);
  for (int i = 0; i < 50; ++i)
    saver.offer(calibration_with_heading(i));
  saver.flush();
  const Calibration back = load_calibration(file.string());
  EXPECT_DOUBLE_EQ(back.heading_deg, 49.0);
  EXPECT_TRUE(back.calibrated[0]);
  EXPECT_GE(saver.writes(), 1u);
  EXPECT_LE(saver.writes(), 50u);
  fs::remove(file);
}

TEST(CalibrationSaver, DestructorWritesWhatIsWaiting) {
  const fs::path file = temp_path("saver-dtor");
  fs::remove(file);
  {
    CalibrationSaver saver(file.string(), nullptr);
    saver.offer(calibration_with_heading(12.5));
  }
  ASSERT_TRUE(fs::exists(file));
  EXPECT_DOUBLE_EQ(load_calibration(file.string()).heading_deg, 12.5);
  fs::remove(file);
}

TEST(CalibrationSaver, UnwritablePathIsLoggedNotThrown) {
  char* buf = nullptr;
  size_t len = 0;
  FILE* mem = open_memstream(&buf, &len);
  ASSERT_NE(mem, nullptr);
  {
    LogSink sink(mem);
    Logger log(sink, "test");
    CalibrationSaver saver("/nonexistent-dir/calibration.toml", &log);
    saver.offer(calibration_with_heading(1));
    saver.flush();
    EXPECT_EQ(saver.writes(), 1u);
  }
  std::fclose(mem);
  const std::string text(buf, len);
  std::free(buf);
  EXPECT_NE(text.find("cannot save calibration"), std::string::npos) << text;
  EXPECT_NE(text.find("/nonexistent-dir"), std::string::npos) << text;
}

}  // namespace
}  // namespace mocap::daemon
