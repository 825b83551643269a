// Helpers for the session tests: deterministic samples/poses/raw bytes from an index, a temp
// directory that removes itself, reading a whole session back, a private mount namespace.
#pragma once

#include <sched.h>
#include <sys/mount.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "mocap/session/session_reader.hpp"
#include "mocap/session/session_writer.hpp"

#include "../common/temp_dir.hpp"

namespace mocap::test {

inline session::SessionHeader make_header() {
  session::SessionHeader h;
  h.t_start_unix_ns = 1'763'000'000'000'000'000;
  h.t_start_host_ns = 123'456'789;
  h.config_text = "[rig]\nname = \"test\"\n[[sensor]]\nname = \"pelvis\"\n";
  h.calibration_text = "q_sensor_segment pelvis 1 0 0 0\n";
  h.sensors = {
      {"pelvis_imu", "witmotion", 0, 0}, {"head_imu", "xsens", 3, 1}, {"spare", "sim", -1, 7}};
  return h;
}

inline ImuSample make_sample(uint32_t i) {
  ImuSample s;
  s.t_host_ns = 1'000'000 + static_cast<int64_t>(i) * 10'000'000;
  s.t_device_ns = static_cast<int64_t>(i) * 9'999'000;
  s.seq = i;
  s.sensor_id = static_cast<uint16_t>(i % 3);
  s.valid = kFieldGyr | kFieldAcc | (i % 2 ? kFieldMag : 0);
  s.flags = static_cast<uint8_t>(i % 5 == 0 ? kFlagGapBefore : 0);
  s.gyr_rad_s = {0.1 * i, -0.2, 1e-9 * i};
  s.acc_m_s2 = {0.01, 9.81, -0.5 * std::sin(i)};
  s.mag_uT = {30.5, -12.25, 41.0 + i};
  s.q_device_sensor = Eigen::Quaterniond(std::cos(0.01 * i), 0, 0, std::sin(0.01 * i));
  return s;
}

inline PoseFrame make_pose(uint64_t i, uint32_t sensors = 3) {
  PoseFrame f;
  reset_pose(f);
  f.frame = i;
  f.t_ns = 5'000'000 + static_cast<int64_t>(i) * 10'000'000;
  f.flags = kFrameRecording | (i % 2 ? kFrameCalibrated : 0u);
  f.sensor_count = sensors;
  f.calib_countdown_s = 0.5f;
  for (int s = 0; s < kSegmentCount; ++s) {
    const float a = 0.001f * static_cast<float>(i + s);
    f.q_earth_segment[s] = {std::cos(a), 0, std::sin(a), 0};
    f.p_earth_segment_m[s] = {0.01f * s, 0.02f * static_cast<float>(i % 7), 0.9f};
    f.q_parent_segment[s] = {std::cos(a / 3), std::sin(a / 3), 0, 0};
    f.joint_violation_deg[s] = static_cast<float>(s % 3);
    f.segment_flags[s] = kSegTracked | (s == 12 ? kSegStance : 0u);
  }
  for (uint32_t k = 0; k < sensors; ++k) {
    std::snprintf(f.sensors[k].name, sizeof f.sensors[k].name, "imu_%u", k);
    f.sensors[k].segment = static_cast<int8_t>(k);
    f.sensors[k].state = 2;
    f.sensors[k].rate_hz = 100.5f;
    f.sensors[k].drops = k + static_cast<uint32_t>(i);
    f.sensors[k].heading_sigma_deg = 3.25f;
  }
  return f;
}

inline std::vector<uint8_t> make_raw(uint32_t i, std::size_t n) {
  std::vector<uint8_t> b(n);
  for (std::size_t k = 0; k < n; ++k)
    b[k] = static_cast<uint8_t>((k * 31 + i * 7) & 0xff);
  return b;
}

inline bool same_sample(const ImuSample& a, const ImuSample& b) {
  return a.t_host_ns == b.t_host_ns && a.t_device_ns == b.t_device_ns && a.seq == b.seq &&
         a.sensor_id == b.sensor_id && a.valid == b.valid && a.flags == b.flags &&
         a.gyr_rad_s == b.gyr_rad_s && a.acc_m_s2 == b.acc_m_s2 && a.mag_uT == b.mag_uT &&
         a.q_device_sensor.coeffs() == b.q_device_sensor.coeffs();
}

inline bool same_pose(const PoseFrame& a, const PoseFrame& b) {
  if (a.frame != b.frame || a.t_ns != b.t_ns || a.flags != b.flags ||
      a.sensor_count != b.sensor_count || a.calib_countdown_s != b.calib_countdown_s ||
      a.q_earth_segment != b.q_earth_segment || a.p_earth_segment_m != b.p_earth_segment_m ||
      a.q_parent_segment != b.q_parent_segment || a.joint_violation_deg != b.joint_violation_deg ||
      a.segment_flags != b.segment_flags)
    return false;
  for (uint32_t k = 0; k < a.sensor_count; ++k) {
    const auto &x = a.sensors[k], &y = b.sensors[k];
    if (std::string(x.name) != y.name || x.segment != y.segment || x.state != y.state ||
        x.flags != y.flags || x.rate_hz != y.rate_hz || x.last_age_ms != y.last_age_ms ||
        x.drops != y.drops || x.errors != y.errors || x.gyro_bias_dps != y.gyro_bias_dps ||
        x.heading_sigma_deg != y.heading_sigma_deg)
      return false;
  }
  return true;
}

inline std::vector<uint8_t> slurp(const std::string& path) {
  std::vector<uint8_t> b;
  if (std::FILE* f = std::fopen(path.c_str(), "rb")) {
    uint8_t buf[65536];
    std::size_t n;
    while ((n = std::fread(buf, 1, sizeof buf, f)) > 0)
      b.insert(b.end(), buf, buf + n);
    std::fclose(f);
  }
  return b;
}

/// Gives this test process its own mount namespace so test mounts vanish with it.
inline bool private_mounts(std::string& why) {
  if (::unshare(CLONE_NEWNS) != 0) {
    why = std::string("unshare(CLONE_NEWNS): ") + std::strerror(errno);
    return false;
  }
  if (::mount(nullptr, "/", nullptr, MS_REC | MS_PRIVATE, nullptr) != 0) {
    why = std::string("make / private: ") + std::strerror(errno);
    return false;
  }
  return true;
}

/// "" if this process may mount test file systems (it is root, and has just been given its own
/// mount namespace so the mounts vanish with it), else why not (the test skips).
inline std::string test_mounts_unavailable() {
  if (::geteuid() != 0) return "not root";
  std::string why;
  return private_mounts(why) ? "" : why;
}

/// Mounts a 64 KiB tmpfs on `dir` (flags: 0 or MS_RDONLY); "" or what failed.
inline std::string mount_small_tmpfs(const std::string& dir, unsigned long flags = 0) {
  if (::mount("tmpfs", dir.c_str(), "tmpfs", flags, "size=64k") == 0) return "";
  return std::strerror(errno);
}

}  // namespace mocap::test
