// HeadingFromMotion: a sensor's heading alignment from its motion against its reference's.
#include "mocap/rig/heading_from_motion.hpp"

#include <algorithm>
#include <cmath>

namespace mocap::rig {

void HeadingFromMotion::reset(const std::array<int, kSegmentCount>& reference) {
  active_ = false;
  for (int s = 0; s < kSegmentCount; ++s) {
    fit_[s] = Fit{.ref = reference[s]};
    active_ = active_ || reference[s] >= 0;
  }
}

void HeadingFromMotion::restart(int seg, int reference) {
  if (seg < 0 || seg >= kSegmentCount) return;
  fit_[seg] = Fit{.ref = reference};
  active_ = active_ || reference >= 0;
}

void HeadingFromMotion::seed(int seg, double weight) {
  if (seg < 0 || seg >= kSegmentCount || fit_[seg].ref < 0 || !(weight > 0)) return;
  fit_[seg].sum.x() += weight;
}

void HeadingFromMotion::add_reference(int seg, const Eigen::Vector3d& v, int64_t t_ns) {
  if (seg < 0 || seg >= kSegmentCount || fit_[seg].ref < 0 || !v.allFinite()) return;
  Fit& f = fit_[seg];
  f.ref_v = v.head<2>();
  f.ref_t_ns = t_ns;
  f.ref_pending = true;
  pair(f);
}

void HeadingFromMotion::add(int seg, const Eigen::Vector3d& v, int64_t t_ns) {
  if (seg < 0 || seg >= kSegmentCount || fit_[seg].ref < 0 || !v.allFinite()) return;
  Fit& f = fit_[seg];
  f.prev_v = f.v;
  f.prev_t_ns = f.t_ns;
  f.have_prev = f.have;
  f.v = v.head<2>();
  f.t_ns = t_ns;
  f.have = true;
  pair(f);
}

void HeadingFromMotion::pair(Fit& f) {
  // Each reference sample is paired once, with the segment's signal at its time: interpolated
  // between the segment's two samples around it (sensors sample at their own instants; pairing
  // with the newest one instead turns the fit by the angle the acceleration turns meanwhile),
  // or the segment's newer sample within max_pair_age_s.
  if (!f.ref_pending || !f.have || f.t_ns < f.ref_t_ns) return;  // wait for it
  f.ref_pending = false;
  const int64_t t = f.ref_t_ns;
  const int64_t max_age_ns = static_cast<int64_t>(opt_.max_pair_age_s * 1e9);
  Eigen::Vector2d a = f.v;
  if (f.have_prev && f.prev_t_ns <= t && f.t_ns - f.prev_t_ns <= 2 * max_age_ns) {
    const int64_t span = f.t_ns - f.prev_t_ns;
    const double u = span > 0 ? static_cast<double>(t - f.prev_t_ns) / span : 1.0;
    a = f.prev_v + u * (f.v - f.prev_v);
  } else if (f.t_ns - t > max_age_ns) {
    return;  // no segment sample near the reference's
  }
  const double dt_s =
      f.have_pair ? std::clamp(static_cast<double>(t - f.pair_t_ns) * 1e-9, 0.0, 0.1) : 0.0;
  f.pair_t_ns = t;
  f.have_pair = true;
  if (dt_s <= 0) return;
  const Eigen::Vector2d& b = f.ref_v;
  const double keep = std::exp(-dt_s / opt_.tau_s);
  const double ab = a.norm() * b.norm();
  const double w = 1.0 / (1.0 + ab / opt_.saturation);
  // |a||b| (cos, sin) of the angle from a to b, weighted.
  f.sum = keep * f.sum + dt_s * w * Eigen::Vector2d(a.dot(b), a.x() * b.y() - a.y() * b.x());
  f.evidence = keep * f.evidence + dt_s * w * ab;
}

bool HeadingFromMotion::estimate(int seg, double& yaw_rad) const {
  if (seg < 0 || seg >= kSegmentCount) return false;
  const Fit& f = fit_[seg];
  if (f.ref < 0 || f.evidence < opt_.min_evidence) return false;
  // A consistent direction is needed, not only motion: the resultant must carry a fair share of
  // the evidence (uncorrelated signals give a short resultant).
  if (f.sum.norm() < 0.3 * f.evidence) return false;
  yaw_rad = std::atan2(f.sum.y(), f.sum.x());
  return true;
}

bool HeadingFromMotion::settling(int seg) const {
  if (seg < 0 || seg >= kSegmentCount) return false;
  const Fit& f = fit_[seg];
  return f.ref >= 0 && f.evidence < opt_.settle_evidence &&
         f.sum.norm() >= opt_.settle_coherence * f.evidence;
}

double HeadingFromMotion::evidence(int seg) const {
  return seg >= 0 && seg < kSegmentCount && fit_[seg].ref >= 0 ? fit_[seg].evidence : 0.0;
}

void HeadingFromMotion::reference_turned(int seg, double yaw_rad) {
  if (seg < 0 || seg >= kSegmentCount) return;
  Fit& f = fit_[seg];
  // The reference's later signals turn by yaw_rad: the angles summed so far grow by it.
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  f.sum = Eigen::Vector2d(c * f.sum.x() - s * f.sum.y(), s * f.sum.x() + c * f.sum.y());
  f.ref_v = Eigen::Vector2d(c * f.ref_v.x() - s * f.ref_v.y(), s * f.ref_v.x() + c * f.ref_v.y());
}

void HeadingFromMotion::applied(int seg, double yaw_rad) {
  if (seg < 0 || seg >= kSegmentCount) return;
  Fit& f = fit_[seg];
  // The segment's later signals turn by yaw_rad: the angles summed so far shrink by it.
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  f.sum = Eigen::Vector2d(c * f.sum.x() + s * f.sum.y(), c * f.sum.y() - s * f.sum.x());
  // The segment's samples not yet paired are in the old frame: turned as its later ones.
  const auto turn = [&](const Eigen::Vector2d& u) {
    return Eigen::Vector2d(c * u.x() - s * u.y(), s * u.x() + c * u.y());
  };
  f.v = turn(f.v);
  f.prev_v = turn(f.prev_v);
}

}  // namespace mocap::rig
