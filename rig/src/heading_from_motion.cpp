// HeadingFromMotion: a sensor's heading alignment from its motion against its reference's.
#include "mocap/rig/heading_from_motion.hpp"

#include <algorithm>
#include <cmath>

namespace mocap::rig {

void HeadingFromMotion::reset(const std::array<int, kSegmentCount>& reference) {
  ref_ = reference;
  active_ = false;
  for (int s = 0; s < kSegmentCount; ++s) {
    have_[s] = false;
    have_prev_[s] = false;
    have_pair_[s] = false;
    ref_pending_[s] = false;
    sum_[s].setZero();
    evidence_[s] = 0;
    active_ = active_ || ref_[s] >= 0;
  }
}

void HeadingFromMotion::restart(int seg, int reference) {
  if (seg < 0 || seg >= kSegmentCount) return;
  ref_[seg] = reference;
  active_ = active_ || reference >= 0;
  have_[seg] = false;
  have_prev_[seg] = false;
  have_pair_[seg] = false;
  ref_pending_[seg] = false;
  sum_[seg].setZero();
  evidence_[seg] = 0;
}

void HeadingFromMotion::add_reference(int seg, const Eigen::Vector3d& v, int64_t t_ns) {
  if (seg < 0 || seg >= kSegmentCount || ref_[seg] < 0 || !v.allFinite()) return;
  ref_v_[seg] = v.head<2>();
  ref_t_ns_[seg] = t_ns;
  ref_pending_[seg] = true;
  pair(seg);
}

void HeadingFromMotion::add(int seg, const Eigen::Vector3d& v, int64_t t_ns) {
  if (seg < 0 || seg >= kSegmentCount || ref_[seg] < 0 || !v.allFinite()) return;
  prev_v_[seg] = v_[seg];
  prev_t_ns_[seg] = t_ns_[seg];
  have_prev_[seg] = have_[seg];
  v_[seg] = v.head<2>();
  t_ns_[seg] = t_ns;
  have_[seg] = true;
  pair(seg);
}

void HeadingFromMotion::pair(int seg) {
  // Each reference sample is paired once, with the segment's signal at its time: interpolated
  // between the segment's two samples around it (sensors sample at their own instants; pairing
  // with the newest one instead turns the fit by the angle the acceleration turns meanwhile),
  // or the segment's newer sample within max_pair_age_s.
  if (!ref_pending_[seg] || !have_[seg] || t_ns_[seg] < ref_t_ns_[seg]) return;  // wait for it
  ref_pending_[seg] = false;
  const int64_t t = ref_t_ns_[seg];
  const int64_t max_age_ns = static_cast<int64_t>(opt_.max_pair_age_s * 1e9);
  Eigen::Vector2d a = v_[seg];
  if (have_prev_[seg] && prev_t_ns_[seg] <= t && t_ns_[seg] - prev_t_ns_[seg] <= 2 * max_age_ns) {
    const int64_t span = t_ns_[seg] - prev_t_ns_[seg];
    const double f = span > 0 ? static_cast<double>(t - prev_t_ns_[seg]) / span : 1.0;
    a = prev_v_[seg] + f * (v_[seg] - prev_v_[seg]);
  } else if (t_ns_[seg] - t > max_age_ns) {
    return;  // no segment sample near the reference's
  }
  const double dt_s =
      have_pair_[seg] ? std::clamp(static_cast<double>(t - pair_t_ns_[seg]) * 1e-9, 0.0, 0.1) : 0.0;
  pair_t_ns_[seg] = t;
  have_pair_[seg] = true;
  if (dt_s <= 0) return;
  const Eigen::Vector2d& b = ref_v_[seg];
  const double keep = std::exp(-dt_s / opt_.tau_s);
  const double ab = a.norm() * b.norm();
  const double w = 1.0 / (1.0 + ab / opt_.saturation);
  // |a||b| (cos, sin) of the angle from a to b, weighted.
  sum_[seg] =
      keep * sum_[seg] + dt_s * w * Eigen::Vector2d(a.dot(b), a.x() * b.y() - a.y() * b.x());
  evidence_[seg] = keep * evidence_[seg] + dt_s * w * ab;
}

bool HeadingFromMotion::estimate(int seg, double& yaw_rad) const {
  if (seg < 0 || seg >= kSegmentCount || ref_[seg] < 0 || evidence_[seg] < opt_.min_evidence)
    return false;
  // A consistent direction is needed, not only motion: the resultant must carry a fair share of
  // the evidence (uncorrelated signals give a short resultant).
  if (sum_[seg].norm() < 0.3 * evidence_[seg]) return false;
  yaw_rad = std::atan2(sum_[seg].y(), sum_[seg].x());
  return true;
}

bool HeadingFromMotion::settling(int seg) const {
  if (seg < 0 || seg >= kSegmentCount || ref_[seg] < 0) return false;
  return evidence_[seg] < opt_.settle_evidence &&
         sum_[seg].norm() >= opt_.settle_coherence * evidence_[seg];
}

void HeadingFromMotion::applied(int seg, double yaw_rad) {
  if (seg < 0 || seg >= kSegmentCount) return;
  // The segment's later signals turn by yaw_rad: the angles summed so far shrink by it.
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  const Eigen::Vector2d v = sum_[seg];
  sum_[seg] = Eigen::Vector2d(c * v.x() + s * v.y(), c * v.y() - s * v.x());
  // The segment's samples not yet paired are in the old frame: turned as its later ones.
  const auto turn = [&](const Eigen::Vector2d& u) {
    return Eigen::Vector2d(c * u.x() - s * u.y(), s * u.x() + c * u.y());
  };
  v_[seg] = turn(v_[seg]);
  prev_v_[seg] = turn(prev_v_[seg]);
}

}  // namespace mocap::rig
