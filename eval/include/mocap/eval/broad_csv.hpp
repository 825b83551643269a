// Reader for IMU sample CSVs in the BROAD layout (/work/shared/datasets/broad/): optional
// "# name, RATE Hz" comment, a header naming the columns, one sample per line; plain or gzip.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace mocap {

/// One recording: time, gyro (rad/s), acc (m/s^2), mag (uT), optional reference orientation
/// (sensor -> ENU; NaN where unknown) and movement mask.
struct BroadTrial {
  std::string name;
  double rate_hz = 0;  ///< from the comment line, else from the t column
  bool has_mag = false, has_ref = false, has_movement = false;
  std::vector<double> t_s;
  std::vector<Eigen::Vector3d> gyr_rad_s, acc_m_s2, mag_uT;
  std::vector<Eigen::Vector4d> ref_wxyz;  ///< reference quaternion w,x,y,z (NaN = missing)
  std::vector<uint8_t> movement;
  /// Per-sample SampleFlag bits (empty: none; clip_gyro sets kFlagGyrClipped).
  std::vector<uint8_t> flags;

  size_t size() const { return t_s.size(); }
};

/// The gyro as a sensor of full scale +-range_dps would read it: each axis clipped, the sample
/// flagged (kFlagSaturated | kFlagGyrClipped) as a driver does. Returns the clipped samples.
size_t clip_gyro(BroadTrial& trial, double range_dps);

/// Parses CSV text. On failure returns false and sets error to "line N: what is wrong".
/// Required columns: t, gyr_x..z, acc_x..z; optional: mag_x..z, ref_w..z, movement.
bool parse_broad_csv(std::string_view text, BroadTrial& out, std::string& error);

/// Reads a file (gzip or plain, detected by content) and parses it. error names the file.
bool read_broad_csv(const std::string& path, BroadTrial& out, std::string& error);

/// Lists the *.csv / *.csv.gz files of a directory, sorted by name.
std::vector<std::string> list_broad_trials(const std::string& dir);

/// <source>/../shared/datasets/broad, where the development trials live (the MOCAP_BROAD_DIR
/// compile definition of mocap_eval).
std::string default_broad_dir();

}  // namespace mocap
