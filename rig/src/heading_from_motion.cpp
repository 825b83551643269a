// HeadingFromMotion: a sensor's heading alignment from its rate against its reference segment's.
#include "mocap/rig/heading_from_motion.hpp"

#include <cmath>

namespace mocap::rig {

void HeadingFromMotion::reset(const std::array<int, kSegmentCount>& reference) {
  ref_ = reference;
  active_ = false;
  for (int s = 0; s < kSegmentCount; ++s) {
    have_[s] = false;
    sum_[s].setZero();
    evidence_[s] = 0;
    active_ = active_ || ref_[s] >= 0;
  }
}

void HeadingFromMotion::add(int seg, const Eigen::Vector3d& w, int64_t t_ns) {
  if (seg < 0 || seg >= kSegmentCount || !w.allFinite()) return;
  const Eigen::Vector2d a = w.head<2>();
  const int r = ref_[seg];
  if (r >= 0 && have_[seg] && have_[r]) {
    const double dt_s = std::clamp(static_cast<double>(t_ns - last_t_ns_[seg]) * 1e-9, 0.0, 0.1);
    const bool paired =
        std::abs(static_cast<double>(t_ns - last_t_ns_[r]) * 1e-9) <= opt_.max_pair_age_s;
    if (paired && dt_s > 0) {
      const Eigen::Vector2d& b = last_w_[r];
      const double keep = std::exp(-dt_s / opt_.tau_s);
      // |a||b| (cos, sin) of the angle from a to b.
      sum_[seg] =
          keep * sum_[seg] + dt_s * Eigen::Vector2d(a.dot(b), a.x() * b.y() - a.y() * b.x());
      evidence_[seg] = keep * evidence_[seg] + dt_s * a.norm() * b.norm();
    }
  }
  last_w_[seg] = a;
  last_t_ns_[seg] = t_ns;
  have_[seg] = true;
}

bool HeadingFromMotion::estimate(int seg, double& yaw_rad) const {
  if (seg < 0 || seg >= kSegmentCount || ref_[seg] < 0 || evidence_[seg] < opt_.min_evidence)
    return false;
  // A consistent direction is needed, not only rates: the resultant must carry a fair share of
  // the evidence (uncorrelated rates give a short resultant).
  if (sum_[seg].norm() < 0.3 * evidence_[seg]) return false;
  yaw_rad = std::atan2(sum_[seg].y(), sum_[seg].x());
  return true;
}

void HeadingFromMotion::applied(int seg, double yaw_rad) {
  if (seg < 0 || seg >= kSegmentCount) return;
  // The segment's later rates turn by yaw_rad: the angles summed so far shrink by it.
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  const Eigen::Vector2d v = sum_[seg];
  sum_[seg] = Eigen::Vector2d(c * v.x() + s * v.y(), c * v.y() - s * v.x());
}

}  // namespace mocap::rig
