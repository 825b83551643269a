// Writers for the simulator's offline files: the interchange IMU CSV
// `t,sensor,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z,mag_x,mag_y,mag_z` (s, rad/s, m/s^2, uT; sensor =
// name) and the ground-truth pose CSV `t,segment,w,x,y,z,px,py,pz` (s, earth ENU, metres).
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "mocap/core/imu_sample.hpp"
#include "mocap/sim/body_pose.hpp"

namespace mocap::sim {

/// A CSV file opened for writing; throws std::runtime_error naming the path if it cannot be
/// opened or written.
class CsvFile {
 public:
  CsvFile(const std::string& path, std::string_view header);
  ~CsvFile();
  CsvFile(const CsvFile&) = delete;
  CsvFile& operator=(const CsvFile&) = delete;
  /// Flushes and closes; throws if any write failed.
  void close();

 protected:
  std::FILE* f_ = nullptr;
  std::string path_;
};

/// Interchange IMU CSV. `sensor_names[sensor_id]` names each sensor; t = (t_host_ns - t0_ns) s.
class ImuCsvWriter : public CsvFile {
 public:
  static constexpr std::string_view kHeader =
      "t,sensor,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z,mag_x,mag_y,mag_z";
  ImuCsvWriter(const std::string& path, std::vector<std::string> sensor_names, int64_t t0_ns);
  void write(const ImuSample& s);

 private:
  std::vector<std::string> names_;
  int64_t t0_ns_;
};

/// Ground-truth pose CSV: one row per segment per frame (joint position, earth orientation).
class TruthCsvWriter : public CsvFile {
 public:
  static constexpr std::string_view kHeader = "t,segment,w,x,y,z,px,py,pz";
  explicit TruthCsvWriter(const std::string& path);
  void write(const TruthFrame& f);
};

}  // namespace mocap::sim
