// Kinematic heading coupling at the knees and elbows (heading_coupling.hpp).
#include "mocap/skeleton/heading_coupling.hpp"

#include <algorithm>
#include <cmath>

#include "mocap/skeleton/quat_math.hpp"

namespace mocap {

HeadingCoupling::HeadingCoupling(RigMapping rig, HeadingCouplingOptions options)
    : rig_(rig), opt_(options) {
  if (opt_.enabled && opt_.history_samples > 0)
    hist_.resize(kCouplingPairs.size() * static_cast<size_t>(opt_.history_samples));
  reset();
}

void HeadingCoupling::reset() {
  corr_.fill(0.0);
  trust_.fill(1.0);
  hinge_.fill(CouplingHinge{});
  t_last_ns_.fill(0);
  hist_head_.fill(0);
  hist_size_.fill(0);
  base_.fill(CouplingHinge{});
}

bool HeadingCoupling::step(const Eigen::Quaterniond& qp, const Eigen::Quaterniond& qc, double dt_s,
                           double& offset, CouplingHinge& st) const {
  const Eigen::Vector3d ap = qp * Eigen::Vector3d::UnitY();
  const Eigen::Vector3d ac = qc * Eigen::Vector3d::UnitY();
  const bool observable =
      dt_s > 0 && rotation_angle_rad(qp.conjugate() * qc) >= opt_.min_flex_deg * kDegToRad &&
      ap.head<2>().norm() >= opt_.min_axis_horizontal &&
      ac.head<2>().norm() >= opt_.min_axis_horizontal &&
      std::abs(ap.z() - ac.z()) <= opt_.max_elevation_mismatch;
  if (!observable) return false;
  // Azimuth of the child's axis minus the parent's: the heading offset between them.
  const double measured =
      std::remainder(std::atan2(ac.y(), ac.x()) - std::atan2(ap.y(), ap.x()), 2 * M_PI);
  if (!std::isfinite(measured)) return false;
  const double cap = opt_.max_correction_deg * kDegToRad;
  const double max_res = opt_.max_residual_deg * kDegToRad;
  const double residual = std::remainder(measured - offset, 2 * M_PI);
  const double gain = 1.0 - std::exp(-dt_s / opt_.tau_s);
  offset = std::clamp(offset + gain * std::clamp(residual, -max_res, max_res), -cap, cap);
  st.offset_deg = offset * kRadToDeg;
  st.last_residual_deg = std::remainder(measured - offset, 2 * M_PI) * kRadToDeg;
  st.observed_s += dt_s;
  return true;
}

void HeadingCoupling::push(size_t h, const Frame& f) {
  const size_t cap = static_cast<size_t>(opt_.history_samples);
  Frame* ring = hist_.data() + h * cap;
  if (hist_size_[h] == cap) {
    // The oldest frame leaves the window: fold it into the state before the window.
    const Frame& old = ring[hist_head_[h]];
    double offset = base_[h].offset_deg * kDegToRad;
    step(old.q_parent, old.q_child, old.dt_s, offset, base_[h]);
    hist_head_[h] = (hist_head_[h] + 1) % cap;
    --hist_size_[h];
  }
  ring[(hist_head_[h] + hist_size_[h]) % cap] = f;
  ++hist_size_[h];
}

void HeadingCoupling::rebase(const Calibration& from, const Calibration& to) {
  if (!opt_.enabled || hist_.empty()) return;
  const size_t cap = static_cast<size_t>(opt_.history_samples);
  // q_to = L * q_from * R with L = c_to * c_from^-1 (earth side), R = m_from^-1 * m_to (mounting).
  auto map = [&](int s, const Eigen::Quaterniond& q) {
    return (to.q_correction[s] * from.q_correction[s].conjugate() * q *
            from.q_sensor_segment[s].conjugate() * to.q_sensor_segment[s])
        .normalized();
  };
  for (size_t h = 0; h < kCouplingPairs.size(); ++h) {
    const int p = index(kCouplingPairs[h].parent);
    const int c = index(kCouplingPairs[h].child);
    Frame* ring = hist_.data() + h * cap;
    CouplingHinge st = base_[h];
    double offset = st.offset_deg * kDegToRad;
    for (size_t k = 0; k < hist_size_[h]; ++k) {
      Frame& f = ring[(hist_head_[h] + k) % cap];
      f.q_parent = map(p, f.q_parent);
      f.q_child = map(c, f.q_child);
      step(f.q_parent, f.q_child, f.dt_s, offset, st);
    }
    hinge_[h] = st;
  }
}

Eigen::Quaterniond HeadingCoupling::apply(int segment, const Eigen::Quaterniond& q) const {
  if (corr_[segment] == 0) return q;
  return (yaw_rotation(corr_[segment]) * q).normalized();
}

void HeadingCoupling::update(const std::array<Eigen::Quaterniond, kSegmentCount>& q,
                             const std::array<bool, kSegmentCount>& have,
                             const std::array<bool, kSegmentCount>& mag_disturbed, int64_t t_ns) {
  if (!opt_.enabled) return;
  for (size_t h = 0; h < kCouplingPairs.size(); ++h) {
    const int p = index(kCouplingPairs[h].parent);
    const int c = index(kCouplingPairs[h].child);
    if (!rig_.tracked(p) || !rig_.tracked(c) || !have[p] || !have[c]) {
      t_last_ns_[h] = 0;
      continue;
    }
    const double dt_s =
        t_last_ns_[h] == 0
            ? 0.0
            : std::clamp(static_cast<double>(t_ns - t_last_ns_[h]) * 1e-9, 0.0, opt_.max_step_s);
    t_last_ns_[h] = t_ns;
    CouplingHinge& st = hinge_[h];
    // Trust of each side: 1 when clean, disturbed_weight while flagged, smoothed.
    const double k_trust = opt_.trust_tau_s > 0 ? 1.0 - std::exp(-dt_s / opt_.trust_tau_s) : 1.0;
    for (int s : {p, c})
      trust_[s] += k_trust * ((mag_disturbed[s] ? opt_.disturbed_weight : 1.0) - trust_[s]);
    // The measurement, when observable; candidate frames are kept for rebase().
    double offset_rad = st.offset_deg * kDegToRad;
    step(q[p], q[c], dt_s, offset_rad, st);
    if (!hist_.empty() && dt_s > 0 &&
        rotation_angle_rad(q[p].conjugate() * q[c]) >=
            opt_.candidate_flex_fraction * opt_.min_flex_deg * kDegToRad)
      push(h, Frame{q[p], q[c], dt_s});
    // The parent is the reference unless it is flagged disturbed and the child is not: the
    // parent's share of the correction ramps with the trust difference (c_child - c_parent =
    // -offset always).
    const double offset = st.offset_deg * kDegToRad;
    const double span = 1.0 - opt_.disturbed_weight;
    const double share_p = span > 0 ? std::clamp((trust_[c] - trust_[p]) / span, 0.0, 1.0) : 0.0;
    corr_[p] = offset * share_p;
    corr_[c] = -offset * (1.0 - share_p);
    if (opt_.carry_distal) {
      const int d = kCouplingCarry[c];
      if (d >= 0) corr_[d] = corr_[c];
    }
  }
}

}  // namespace mocap
