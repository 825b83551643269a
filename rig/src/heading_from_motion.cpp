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
    have_ref_[s] = false;
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
  have_ref_[seg] = false;
  sum_[seg].setZero();
  evidence_[seg] = 0;
}

void HeadingFromMotion::add_reference(int seg, const Eigen::Vector3d& v, int64_t t_ns) {
  if (seg < 0 || seg >= kSegmentCount || ref_[seg] < 0 || !v.allFinite()) return;
  ref_v_[seg] = v.head<2>();
  ref_t_ns_[seg] = t_ns;
  have_ref_[seg] = true;
}

void HeadingFromMotion::add(int seg, const Eigen::Vector3d& v, int64_t t_ns) {
  if (seg < 0 || seg >= kSegmentCount || ref_[seg] < 0 || !v.allFinite()) return;
  const Eigen::Vector2d a = v.head<2>();
  if (have_[seg] && have_ref_[seg]) {
    const double dt_s = std::clamp(static_cast<double>(t_ns - last_t_ns_[seg]) * 1e-9, 0.0, 0.1);
    const bool paired =
        std::abs(static_cast<double>(t_ns - ref_t_ns_[seg]) * 1e-9) <= opt_.max_pair_age_s;
    if (paired && dt_s > 0) {
      const Eigen::Vector2d& b = ref_v_[seg];
      const double keep = std::exp(-dt_s / opt_.tau_s);
      const double ab = a.norm() * b.norm();
      const double w = 1.0 / (1.0 + ab / opt_.saturation);
      // |a||b| (cos, sin) of the angle from a to b, weighted.
      sum_[seg] =
          keep * sum_[seg] + dt_s * w * Eigen::Vector2d(a.dot(b), a.x() * b.y() - a.y() * b.x());
      evidence_[seg] = keep * evidence_[seg] + dt_s * w * ab;
    }
  }
  last_t_ns_[seg] = t_ns;
  have_[seg] = true;
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

void HeadingFromMotion::applied(int seg, double yaw_rad) {
  if (seg < 0 || seg >= kSegmentCount) return;
  // The segment's later signals turn by yaw_rad: the angles summed so far shrink by it.
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  const Eigen::Vector2d v = sum_[seg];
  sum_[seg] = Eigen::Vector2d(c * v.x() + s * v.y(), c * v.y() - s * v.x());
}

}  // namespace mocap::rig
