// Plain CSV of IMU samples for `mocap replay`: a header naming the columns
//   t,sensor,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z,mag_x,mag_y,mag_z
// (any order; s, rad/s, m/s^2, uT; sensor = a name; empty mag fields = no magnetometer), then one
// sample per line in non-decreasing time. Parsed line by line (streams of any length), strictly:
// every error names the line, the column and the problem.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "mocap/core/imu_sample.hpp"

namespace mocap::daemon {

class SampleCsvParser {
 public:
  explicit SampleCsvParser(std::string source = "samples.csv") : source_(std::move(source)) {}

  /// Feeds one line (without its newline; a trailing '\r' is ignored). The first non-empty line
  /// is the header. Returns 1 and fills `out` for a sample, 0 for a header/blank/comment ('#')
  /// line, -1 on an error (see error()). sample.sensor_id indexes sensors(); t_host_ns is t.
  int feed_line(std::string_view line, ImuSample& out);
  /// Sensor names in order of first appearance.
  const std::vector<std::string>& sensors() const { return sensors_; }
  const std::string& error() const { return error_; }
  uint64_t line_number() const { return line_; }

 private:
  int fail(std::string msg);
  int column_index(std::string_view name) const;

  std::string source_;
  std::string error_;
  uint64_t line_ = 0;
  bool have_header_ = false;
  std::vector<int> col_of_field_;  // field (0 t, 1 sensor, 2..10 values) -> column index
  int columns_ = 0;
  std::vector<std::string> sensors_;
  std::vector<int64_t> last_t_ns_;  // per sensor
  int64_t last_any_t_ns_ = INT64_MIN;
  std::vector<std::string_view> cells_;
};

}  // namespace mocap::daemon
