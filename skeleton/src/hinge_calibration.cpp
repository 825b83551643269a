// Hinge-axis refinement of the calibration's per-segment heading (see hinge_calibration.hpp).
#include "mocap/skeleton/hinge_calibration.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include "mocap/skeleton/quat_math.hpp"

namespace mocap {

namespace {

/// |w x j(phi)|^2 = k(w) + u(w) . (cos 2phi, sin 2phi) for j = (cos phi, sin phi, 0).
void perp_terms(const Eigen::Vector3d& w, double& k, Eigen::Vector2d& u) {
  k = w.z() * w.z() + 0.5 * (w.x() * w.x() + w.y() * w.y());
  u = Eigen::Vector2d(-0.5 * (w.x() * w.x() - w.y() * w.y()), -w.x() * w.y());
}

/// Rotation vector of q (angle * axis), shortest way.
Eigen::Vector3d rotation_vector(Eigen::Quaterniond q) {
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  const Eigen::Vector3d v = q.vec();
  const double s = v.norm();
  if (s < 1e-12) return 2.0 * v;
  return v * (2.0 * std::atan2(s, q.w()) / s);
}

constexpr double kAxisPhi = M_PI / 2;  // flexion axis y: phi = 90 deg in the segment's xy plane

}  // namespace

HingeAxisRefiner::HingeAxisRefiner(RigMapping rig, HingeRefineOptions options)
    : rig_(rig), opt_(options) {
  reset();
}

void HingeAxisRefiner::reset() {
  sums_.fill(Sums{});
  est_.fill(HingeEstimate{});
  n_estimated_.fill(0);
  q_prev_.fill(Eigen::Quaterniond::Identity());
  t_prev_ns_.fill(0);
  have_prev_.fill(false);
  w_.fill(Eigen::Vector3d::Zero());
  t_w_ns_.fill(0);
  dt_w_s_.fill(0.0);
  alpha_.fill(0.0);
  common_ = 0;
  started_ = false;
  t_last_update_ns_ = 0;
}

void HingeAxisRefiner::add(const std::array<Eigen::Quaterniond, kSegmentCount>& q,
                           const std::array<int64_t, kSegmentCount>& t_sample_ns,
                           const std::array<bool, kSegmentCount>& have, int64_t t_ns) {
  if (!opt_.enabled) return;
  if (!started_) {
    started_ = true;
    t_last_update_ns_ = t_ns;
  }
  const int64_t max_step_ns = static_cast<int64_t>(opt_.max_step_s * 1e9);
  // 1. Per-segment rates from each segment's own consecutive samples.
  std::array<bool, kSegmentCount> fresh{};
  for (int i = 0; i < kSegmentCount; ++i) {
    if (!have[i]) {
      have_prev_[i] = false;
      continue;
    }
    const int64_t dt_ns = t_sample_ns[i] - t_prev_ns_[i];
    if (have_prev_[i] && dt_ns <= 0) continue;  // no new sample
    if (have_prev_[i] && dt_ns <= max_step_ns) {
      const Eigen::Vector3d w = rotation_vector(q_prev_[i].conjugate() * q[i]) / (dt_ns * 1e-9);
      if (w.allFinite()) {
        w_[i] = w;
        t_w_ns_[i] = t_sample_ns[i];
        dt_w_s_[i] = dt_ns * 1e-9;
        fresh[i] = true;
      }
    }
    q_prev_[i] = q[i];
    t_prev_ns_[i] = t_sample_ns[i];
    have_prev_[i] = true;
  }
  // 2. Each new child rate with a recent parent rate adds one residual to its hinge.
  const double min_rate = opt_.min_rate_deg_s * kDegToRad;
  for (size_t h = 0; h < kRefinePairs.size(); ++h) {
    const int c = index(kRefinePairs[h].child);
    const int p = index(kRefinePairs[h].parent);
    const int v = kRefinePairs[h].via;
    if (!rig_.tracked(c) || !rig_.tracked(p) || !fresh[c] || t_w_ns_[p] == 0 ||
        std::abs(t_w_ns_[p] - t_w_ns_[c]) > max_step_ns)
      continue;
    const Eigen::Vector3d& wp = w_[p];
    const Eigen::Vector3d& wc = w_[c];
    if (wp.norm() < min_rate && wc.norm() < min_rate) continue;
    if (v >= 0) {
      // The joint between `via` and the child (the wrist) must be still.
      if (!rig_.tracked(v) || !have[v] || t_w_ns_[v] == 0 ||
          std::abs(t_w_ns_[v] - t_w_ns_[c]) > max_step_ns)
        continue;
      const double w_joint = (wc - (q[c].conjugate() * q[v]) * w_[v]).norm();
      const double w_hinge = (wc - (q[c].conjugate() * q[p]) * wp).norm();
      if (w_joint > opt_.via_still_fraction * w_hinge + 0.5 * min_rate) continue;
    }
    double kp, kc;
    Eigen::Vector2d up, uc;
    perp_terms(wp, kp, up);
    perp_terms(wc, kc, uc);
    const Eigen::Vector4d a(up.x(), up.y(), -uc.x(), -uc.y());
    const double b = kp - kc;
    Sums& s = sums_[h];
    s.h.noalias() += a * a.transpose();
    s.g += a * b;
    s.s += b * b;
    const double sc = wp.squaredNorm() + wc.squaredNorm();
    s.scale += sc * sc;
    // Flexion travel: the child's rate relative to the parent, in the child frame.
    const Eigen::Vector3d w_rel = wc - (q[c].conjugate() * q[p]) * wp;
    s.travel_rad += w_rel.norm() * dt_w_s_[c];
    // The parent's rotation about axes other than the hinge axis (y) while the hinge flexes:
    // what pins the parent's yaw.
    if (w_rel.norm() > 2 * min_rate) s.parent_travel_rad += std::hypot(wp.x(), wp.z()) * dt_w_s_[c];
    ++s.n;
  }
}

bool HingeAxisRefiner::estimate(int hinge, HingeEstimate& out) const {
  const Sums& s = sums_[hinge];
  out.travel_deg = s.travel_rad * kRadToDeg;
  if (s.n < 10 || s.scale <= 0) return false;
  const double range = opt_.max_yaw_deg * kDegToRad;
  double bp = 0, bc = 0;
  const double best = minimize(s, range, false, bp, bc);
  out.parent_yaw_deg = bp * kRadToDeg;
  out.child_yaw_deg = bc * kRadToDeg;
  out.applied_child_yaw_deg = out.child_yaw_deg;
  out.rms_residual = std::sqrt(std::max(best, 0.0) / s.scale);
  out.parent_travel_deg = s.parent_travel_rad * kRadToDeg;
  const double edge = range - 0.5 * kDegToRad;
  const bool ok = out.travel_deg >= opt_.min_travel_deg && std::abs(bc) < edge;
  out.parent_valid =
      ok && std::abs(bp) < edge && s.parent_travel_rad >= opt_.min_parent_off_axis_deg * kDegToRad;
  return ok;
}

double HingeAxisRefiner::minimize(const Sums& s, double range, bool parent_fixed, double& yaw_p,
                                  double& yaw_c) {
  // cost(y) = x^T H x + 2 g^T x + s with x = (cos fp, sin fp, cos fc, sin fc), f = 2 (phi + y).
  const auto xvec = [](double yp, double yc) {
    const double fp = 2 * (kAxisPhi + yp), fc = 2 * (kAxisPhi + yc);
    return Eigen::Vector4d(std::cos(fp), std::sin(fp), std::cos(fc), std::sin(fc));
  };
  const auto cost = [&](double yp, double yc) {
    const Eigen::Vector4d x = xvec(yp, yc);
    return x.dot(s.h * x) + 2 * s.g.dot(x) + s.s;
  };
  // Coarse grid (1 deg) for the basin of the global minimum ...
  double best = std::numeric_limits<double>::infinity();
  const double fixed_p = yaw_p;
  const int n_grid = static_cast<int>(std::floor(range * kRadToDeg));
  for (int i = parent_fixed ? 0 : -n_grid; i <= (parent_fixed ? 0 : n_grid); ++i) {
    for (int j = -n_grid; j <= n_grid; ++j) {
      const double yp = parent_fixed ? fixed_p : i * kDegToRad, yc = j * kDegToRad;
      const double v = cost(yp, yc);
      if (v < best) {
        best = v;
        yaw_p = yp;
        yaw_c = yc;
      }
    }
  }
  // ... then damped Newton iterations to its exact minimum. The minimum often lies in a long
  // narrow valley (the two yaws are strongly correlated), where a finite grid around the best
  // node snaps to a point up to degrees away along the valley and jumps between grid points as
  // the data change slightly; the iteration is continuous in the data.
  double lambda = 0;
  for (int it = 0; it < 100; ++it) {
    const double fp = 2 * (kAxisPhi + yaw_p), fc = 2 * (kAxisPhi + yaw_c);
    const Eigen::Vector4d x = xvec(yaw_p, yaw_c);
    const Eigen::Vector4d r = s.h * x + s.g;
    // dx/dy (x depends on yaw_p through entries 0, 1 and on yaw_c through 2, 3).
    Eigen::Matrix<double, 4, 2> dx = Eigen::Matrix<double, 4, 2>::Zero();
    dx(0, 0) = -2 * std::sin(fp);
    dx(1, 0) = 2 * std::cos(fp);
    dx(2, 1) = -2 * std::sin(fc);
    dx(3, 1) = 2 * std::cos(fc);
    Eigen::Vector2d grad = 2 * dx.transpose() * r;
    Eigen::Matrix2d hess = 2 * dx.transpose() * s.h * dx;
    hess(0, 0) -= 8 * r.head<2>().dot(x.head<2>());  // d2x/dy2 = -4 x
    hess(1, 1) -= 8 * r.tail<2>().dot(x.tail<2>());
    if (parent_fixed) {
      grad.x() = 0;
      hess(0, 1) = hess(1, 0) = 0;
      hess(0, 0) = 1;
    }
    const double diag_scale = std::max(std::abs(hess(0, 0)) + std::abs(hess(1, 1)), 1e-300);
    bool improved = false, converged = false;
    for (int tries = 0; tries < 30 && !improved; ++tries) {
      Eigen::Matrix2d m = hess;
      m.diagonal().array() += lambda * diag_scale;
      const Eigen::LDLT<Eigen::Matrix2d> ldlt(m);
      Eigen::Vector2d step = Eigen::Vector2d::Zero();
      if (ldlt.info() == Eigen::Success && ldlt.isPositive()) step = -ldlt.solve(grad);
      const double np = std::clamp(yaw_p + step.x(), -range, range);
      const double nc = std::clamp(yaw_c + step.y(), -range, range);
      const double v = step.allFinite() ? cost(np, nc) : best;
      if (v < best) {
        improved = true;
        converged = std::abs(np - yaw_p) + std::abs(nc - yaw_c) < 1e-10;
        best = v;
        yaw_p = np;
        yaw_c = nc;
        lambda *= 0.25;
      } else {
        lambda = lambda == 0 ? 1e-6 : lambda * 8;
      }
    }
    if (!improved || converged) break;
  }
  return best;
}

bool HingeAxisRefiner::update(int64_t t_ns) {
  if (!opt_.enabled || !started_) return false;
  if (static_cast<double>(t_ns - t_last_update_ns_) * 1e-9 < opt_.update_interval_s) return false;
  t_last_update_ns_ = t_ns;
  for (size_t h = 0; h < kRefinePairs.size(); ++h) {
    // Re-estimate only pairs with new data (the search is ~10^4 cost evaluations).
    if (sums_[h].n != n_estimated_[h]) {
      HingeEstimate e;
      e.valid = estimate(static_cast<int>(h), e);
      est_[h] = e;
      n_estimated_[h] = sums_[h].n;
    }
  }
  // A parent whose yaw the pair does not pin (an upper arm hanging still, or the via pairs,
  // whose parent is not adjacent) gets the mean offset like every unidentified segment; its
  // child's yaw is then the best fit given that parent yaw, not the joint fit's (which lets the
  // unpinned parent yaw wander to anywhere in +-max_yaw_deg and takes the child with it). The
  // mean depends on those children: a few fixed-point passes (each moves it far less than 0.01
  // deg after the second).
  std::array<double, kSegmentCount> alpha{};
  double mean = 0;
  const double range = opt_.max_yaw_deg * kDegToRad;
  for (int pass = 0; pass < 3; ++pass) {
    std::array<bool, kSegmentCount> known{};
    alpha.fill(0.0);
    double sum = 0;
    int n = 0;
    for (size_t h = 0; h < kRefinePairs.size(); ++h) {
      HingeEstimate& e = est_[h];
      if (!e.valid) continue;
      const int c = index(kRefinePairs[h].child);
      const int p = index(kRefinePairs[h].parent);
      const bool own_parent = kRefinePairs[h].via < 0 && e.parent_valid;
      if (!own_parent && kRefinePairs[h].via < 0 && pass > 0) {
        double yp = mean, yc = 0;
        minimize(sums_[h], range, true, yp, yc);
        e.applied_child_yaw_deg = yc * kRadToDeg;
      }
      alpha[c] = e.applied_child_yaw_deg * kDegToRad;
      known[c] = true;
      sum += alpha[c];
      ++n;
      if (own_parent) {
        alpha[p] = e.parent_yaw_deg * kDegToRad;
        known[p] = true;
        sum += alpha[p];
        ++n;
      }
    }
    if (n == 0) return false;
    mean = sum / n;
    for (int i = 0; i < kSegmentCount; ++i)
      if (!known[i]) alpha[i] = mean;
  }
  const bool changed = alpha != alpha_ || mean != common_;
  alpha_ = alpha;
  common_ = mean;
  return changed;
}

int HingeAxisRefiner::valid_hinges() const {
  int n = 0;
  for (size_t h = 0; h < kRefineHingeCount; ++h)
    n += est_[h].valid ? 1 : 0;
  return n;
}

Calibration HingeAxisRefiner::apply(const Calibration& base,
                                    const std::array<double, kSegmentCount>& alpha,
                                    double common_rad) {
  Calibration c = base;
  c.heading_deg = base.heading_deg + common_rad * kRadToDeg;
  for (int i = 0; i < kSegmentCount; ++i) {
    // Every calibrated segment takes the common turn, whatever its own offset (also exactly 0).
    if (!base.calibrated[i]) continue;
    c.q_sensor_segment[i] = (base.q_sensor_segment[i] * yaw_rotation(alpha[i])).normalized();
    c.q_correction[i] = (yaw_rotation(common_rad - alpha[i]) * base.q_correction[i]).normalized();
  }
  return c;
}

}  // namespace mocap
