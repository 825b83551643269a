// Test helpers for the skeleton tests: random rotations, a body pose generator, and sensors
// mounted on segments with known rotations.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <random>

#include "mocap/core/segments.hpp"
#include "mocap/skeleton/quat_math.hpp"

namespace mocap::test {

/// One millisecond in nanoseconds (sample timestamps).
inline constexpr int64_t kMs = 1'000'000;

inline Eigen::Quaterniond random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  return q.normalized();
}

/// Small random rotation with angle up to max_deg.
inline Eigen::Quaterniond random_small_rotation(std::mt19937& rng, double max_deg) {
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::Vector3d axis(u(rng), u(rng), u(rng));
  if (axis.norm() < 1e-6) axis = Eigen::Vector3d::UnitX();
  const double ang = std::abs(u(rng)) * max_deg * kRadPerDeg;
  return Eigen::Quaterniond(Eigen::AngleAxisd(ang, axis.normalized()));
}

/// Earth orientations of all segments from joint rotations (parents first).
inline std::array<Eigen::Quaterniond, kSegmentCount> earth_from_joints(
    const std::array<Eigen::Quaterniond, kSegmentCount>& q_joint) {
  std::array<Eigen::Quaterniond, kSegmentCount> q;
  for (int i = 0; i < kSegmentCount; ++i) {
    const int p = kSegmentParent[i];
    q[i] = p < 0 ? q_joint[i] : (q[p] * q_joint[i]).normalized();
  }
  return q;
}

/// A plausible random posture: each joint rotated by up to max_deg, the root by any yaw.
inline std::array<Eigen::Quaterniond, kSegmentCount> random_pose(std::mt19937& rng,
                                                                 double max_deg) {
  std::array<Eigen::Quaterniond, kSegmentCount> j;
  std::uniform_real_distribution<double> yaw(-M_PI, M_PI);
  j[0] = yaw_rotation(yaw(rng)) * random_small_rotation(rng, 10);
  for (int i = 1; i < kSegmentCount; ++i)
    j[i] = random_small_rotation(rng, max_deg);
  return earth_from_joints(j);
}

}  // namespace mocap::test
