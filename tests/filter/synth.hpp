// Synthetic IMU streams with known truth for the filter tests: a rotation-rate profile is
// integrated finely to the true orientation, and gyro/acc/mag are generated from it with
// optional bias, noise, linear acceleration and magnetic disturbances.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include "mocap/core/imu_sample.hpp"

namespace mocap::test {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

struct SynthConfig {
  double rate_hz = 100;
  double duration_s = 30;
  Eigen::Quaterniond q0 = Eigen::Quaterniond::Identity();  ///< true q_earth_sensor at t=0
  std::function<Eigen::Vector3d(double)> gyr_true = [](double) -> Eigen::Vector3d {
    return Eigen::Vector3d::Zero();
  };
  /// Earth-frame linear acceleration (m/s^2) at time t.
  std::function<Eigen::Vector3d(double)> acc_lin = [](double) -> Eigen::Vector3d {
    return Eigen::Vector3d::Zero();
  };
  /// Earth-frame field (uT) at time t (default: 20 uT north, 45 uT down).
  std::function<Eigen::Vector3d(double)> mag_earth = [](double) -> Eigen::Vector3d {
    return Eigen::Vector3d(0, 20, -45);
  };
  Eigen::Vector3d gyr_bias = Eigen::Vector3d::Zero();
  double gyr_noise = 0.002, acc_noise = 0.02, mag_noise = 0.2;
  int mag_every = 1;  ///< mag in every n-th sample (as a separate sample when > 1)
  unsigned seed = 1;
};

struct SynthStream {
  std::vector<ImuSample> samples;
  std::vector<Eigen::Quaterniond> truth;  ///< per sample, q_earth_sensor
};

inline SynthStream make_stream(const SynthConfig& c) {
  SynthStream out;
  std::mt19937 rng(c.seed);
  std::normal_distribution<double> n01(0, 1);
  auto noise = [&](double s) -> Eigen::Vector3d {
    return Eigen::Vector3d(n01(rng), n01(rng), n01(rng)) * s;
  };
  const double ts = 1.0 / c.rate_hz;
  const int n = static_cast<int>(c.duration_s * c.rate_hz);
  Eigen::Quaterniond q = c.q0;
  const int sub = std::max(2, static_cast<int>(2000.0 / c.rate_hz));  // fine steps per period
  for (int k = 0; k < n; ++k) {
    const double t = k * ts;
    if (k > 0) {  // integrate the true rate over (t - ts, t] in fine steps (midpoint rule)
      for (int j = 0; j < sub; ++j) {
        const double tm = t - ts + (j + 0.5) * ts / sub;
        const Eigen::Vector3d w = c.gyr_true(tm) * (ts / sub);
        const double a = w.norm();
        if (a > 0) q = q * Eigen::Quaterniond(Eigen::AngleAxisd(a, w / a));
      }
      q.normalize();
    }
    ImuSample s;
    s.t_host_ns = static_cast<int64_t>(std::llround(t * 1e9));
    s.seq = static_cast<uint32_t>(k);
    s.valid = kFieldGyr | kFieldAcc;
    // Gyro: the mean rate over the last period (what a real sensor's output filter gives).
    Eigen::Vector3d wm = Eigen::Vector3d::Zero();
    for (int j = 0; j < sub; ++j)
      wm += c.gyr_true(t - ts + (j + 0.5) * ts / sub);
    s.gyr_rad_s = wm / sub + c.gyr_bias + noise(c.gyr_noise);
    const Eigen::Quaterniond qi = q.conjugate();
    s.acc_m_s2 = qi * (Eigen::Vector3d(0, 0, 9.81) + c.acc_lin(t)) + noise(c.acc_noise);
    const Eigen::Vector3d m = qi * c.mag_earth(t) + noise(c.mag_noise);
    if (c.mag_every <= 1) {
      s.valid |= kFieldMag;
      s.mag_uT = m;
    }
    out.samples.push_back(s);
    out.truth.push_back(q);
    if (c.mag_every > 1 && k % c.mag_every == 0) {
      ImuSample sm;
      sm.t_host_ns = s.t_host_ns;
      sm.valid = kFieldMag;
      sm.mag_uT = m;
      out.samples.push_back(sm);
      out.truth.push_back(q);
    }
  }
  return out;
}

/// Angle between two orientations and its tilt / heading parts (degrees).
inline double angle_deg(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return a.angularDistance(b) / kDeg;
}
inline double tilt_deg(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  const Eigen::Vector3d za = a.conjugate() * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d zb = b.conjugate() * Eigen::Vector3d::UnitZ();
  return std::acos(std::clamp(za.dot(zb), -1.0, 1.0)) / kDeg;
}
/// Signed heading part of the error of est against truth: the error rotation's turn of the
/// earth x axis about earth z, degrees.
inline double heading_err_deg(const Eigen::Quaterniond& est, const Eigen::Quaterniond& truth) {
  const Eigen::Vector3d x = (est * truth.conjugate()) * Eigen::Vector3d::UnitX();
  return std::atan2(x.y(), x.x()) / kDeg;
}

}  // namespace mocap::test
