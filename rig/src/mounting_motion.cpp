// MountingMotion: facings from the tilt of each segment in the mounting motion (see
// mounting_motion.hpp).
#include "mocap/rig/mounting_motion.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "mocap/core/units.hpp"
#include "mocap/skeleton/quat_math.hpp"

namespace mocap::rig {

int MountingMotion::tilt_sign(int s) {
  switch (static_cast<Segment>(s)) {
    case Segment::thigh_l:
    case Segment::thigh_r:
    case Segment::forearm_l:
    case Segment::forearm_r:
    case Segment::hand_l:
    case Segment::hand_r:
      return 1;
    case Segment::foot_l:
    case Segment::foot_r:
    case Segment::neck:
      return 0;
    default:
      return -1;
  }
}

void MountingMotion::start(const PoseCapture& capture, int64_t t_start_ns, double duration_s) {
  capture_ = capture;
  active_ = true;
  t_start_ns_ = t_start_ns;
  t_end_ns_ = t_start_ns + static_cast<int64_t>(duration_s * 1e9);
  for (int s = 0; s < kSegmentCount; ++s) {
    up0_[s] = capture.up_sensor(s);
    sum_[s].setZero();
    spread_[s].setZero();
    max_tilt_[s] = 0;
  }
}

void MountingMotion::add(int s, const Eigen::Quaterniond& q, int64_t t_ns) {
  if (!active_ || s < 0 || s >= kSegmentCount || t_ns < t_start_ns_ || t_ns > t_end_ns_ ||
      !capture_.have[s] || !q.coeffs().allFinite())
    return;
  const Eigen::Vector3d up = q.normalized().conjugate() * Eigen::Vector3d::UnitZ();
  Eigen::Vector3d d = up - up0_[s];
  d -= d.dot(up0_[s]) * up0_[s];
  const double n = d.norm();
  sum_[s] += n * d;
  spread_[s].noalias() += d * d.transpose();
  max_tilt_[s] = std::max(max_tilt_[s], n);
}

std::array<Facing, kSegmentCount> MountingMotion::finish() {
  std::array<Facing, kSegmentCount> out{};
  active_ = false;
  const double min_chord = 2 * std::sin(0.5 * kMinTiltDeg * kRadPerDeg);
  for (int s = 0; s < kSegmentCount; ++s) {
    const int sign = tilt_sign(s);
    if (!capture_.have[s] || sign == 0 || max_tilt_[s] < min_chord) continue;
    const double evidence = spread_[s].trace();
    if (sum_[s].norm() < kMinConsistency * evidence) continue;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(spread_[s]);
    const double major = es.eigenvalues()[2], minor = std::max(es.eigenvalues()[1], 0.0);
    const double spread_deg = std::atan(std::sqrt(minor / std::max(major, 1e-12))) * kDegPerRad;
    const Eigen::Vector3d forward_sensor = sign * sum_[s].normalized();
    out[s] = facing_from_axis(capture_, s, forward_sensor, std::max(kSigmaFloorDeg, spread_deg),
                              AlignSource::motion);
  }
  return out;
}

}  // namespace mocap::rig
