// A minimal PoseEngine for pipeline tests: integrates each sensor's gyro into an orientation
// and uses it as its segment's orientation, recording the calls it receives.
#pragma once

#include <Eigen/Geometry>
#include <array>

#include "mocap/daemon/pose_engine.hpp"

namespace mocap::test {

class GyroEngine final : public daemon::PoseEngine {
 public:
  std::array<Eigen::Quaterniond, kMaxSensors> q{};
  std::array<int64_t, kMaxSensors> last_t{};
  std::array<int, kMaxSensors> segment{};
  std::array<bool, kMaxSensors> live{};
  int calibrations = 0, heading_resets = 0;
  uint64_t samples = 0;

  GyroEngine() {
    for (auto& x : q)
      x.setIdentity();
    segment.fill(-1);
  }
  void on_sample(int i, const ImuSample& s) override {
    if (last_t[i] != 0) {
      const double dt = (s.t_host_ns - last_t[i]) * 1e-9;
      const Eigen::Vector3d w = s.gyr_rad_s * dt;
      if (w.norm() > 0)
        q[i] =
            (q[i] * Eigen::Quaterniond(Eigen::AngleAxisd(w.norm(), w.normalized()))).normalized();
    }
    last_t[i] = s.t_host_ns;
    ++samples;
  }
  void set_sensor_live(int i, bool l) override { live[i] = l; }
  void build_frame(int64_t, PoseFrame& out) override {
    for (int i = 0; i < kMaxSensors; ++i) {
      if (segment[i] < 0) continue;
      out.q_earth_segment[segment[i]] = {float(q[i].w()), float(q[i].x()), float(q[i].y()),
                                         float(q[i].z())};
      out.segment_flags[segment[i]] = live[i] ? kSegTracked : kSegInferred;
    }
    if (calibrations) out.flags |= kFrameCalibrated;
  }
  daemon::SensorHealth sensor_health(int) const override {
    daemon::SensorHealth s;
    s.calibrated = calibrations > 0;
    return s;
  }
  void calibrate(daemon::CalibrationPose, bool) override { ++calibrations; }
  void reset_heading() override { ++heading_resets; }
};

}  // namespace mocap::test
