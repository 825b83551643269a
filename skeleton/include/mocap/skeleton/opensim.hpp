// OpenSim/OpenSense orientations table (.sto) writer: what OpenSense's IMU placer and IMU
// inverse kinematics read. Header `DataRate=`, `DataType=Quaternion`, `version=3`,
// `OpenSimVersion=4.1`, `endheader`; then a tab-separated table: `time` and one column per
// virtual IMU named like OpenSim's (pelvis_imu, torso_imu, femur_r_imu, tibia_r_imu,
// calcn_r_imu, humerus_r_imu, radius_r_imu, hand_r_imu, the left side likewise, head_imu when
// the head is tracked), each cell `w,x,y,z`. Each virtual IMU is its segment's frame (aligned
// with the body in the N-pose), expressed in OpenSim's ground frame: x forward, y up, z to the
// right (our x forward, y left, z up: x_o = x, y_o = z, z_o = -y). Rows stream to the file.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "mocap/skeleton/pose_frame.hpp"

namespace mocap {

/// OpenSim IMU column name of each segment ("" for the neck, which OpenSim models lack).
inline constexpr std::array<std::string_view, kSegmentCount> kOpenSimImuNames = {
    "pelvis_imu",  "torso_imu",     "",
    "head_imu",    "humerus_l_imu", "radius_l_imu",
    "hand_l_imu",  "humerus_r_imu", "radius_r_imu",
    "hand_r_imu",  "femur_l_imu",   "tibia_l_imu",
    "calcn_l_imu", "femur_r_imu",   "tibia_r_imu",
    "calcn_r_imu"};

/// Rotation taking our body/earth axes (x fwd, y left, z up) to OpenSim's (x fwd, y up, z right).
Eigen::Quaterniond q_opensim_body();

struct OpenSimWriterOptions {
  double rate_hz = 60.0;  ///< DataRate; row k has time k / rate_hz
};

class OpenSimWriter {
 public:
  /// Opens `path`. Throws std::runtime_error on I/O errors, std::invalid_argument on a bad rate.
  OpenSimWriter(const std::string& path, OpenSimWriterOptions options = {});
  ~OpenSimWriter();
  OpenSimWriter(const OpenSimWriter&) = delete;
  OpenSimWriter& operator=(const OpenSimWriter&) = delete;

  /// Appends one row. The first frame fixes the columns (head_imu if its head is tracked) and
  /// writes the header. Throws std::runtime_error if the write fails.
  void write_frame(const PoseFrame& frame);
  /// Flushes and closes the file (also done by the destructor, which swallows errors).
  void close();
  int frames() const { return frames_; }

 private:
  std::FILE* f_ = nullptr;
  std::string path_;
  OpenSimWriterOptions opt_;
  std::vector<int> columns_;  // segment per column
  int frames_ = 0;
};

}  // namespace mocap
