// Hinge-axis refinement of the calibration's per-segment heading (see hinge_calibration.hpp).
#include "mocap/skeleton/hinge_calibration.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
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
  block_.fill(Quad{});
  est_.fill(HingeEstimate{});
  n_estimated_.fill(0);
  applied_.fill(false);
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
    // The child's rate relative to the parent, in the child frame (the flexion rate).
    const Eigen::Vector3d w_rel = wc - (q[c].conjugate() * q[p]) * wp;
    const double rel = w_rel.norm();
    if (v >= 0) {
      // The joint between `via` and the child (the wrist) must be still.
      if (!rig_.tracked(v) || !have[v] || t_w_ns_[v] == 0 ||
          std::abs(t_w_ns_[v] - t_w_ns_[c]) > max_step_ns)
        continue;
      const double w_joint = (wc - (q[c].conjugate() * q[v]) * w_[v]).norm();
      if (w_joint > opt_.via_still_fraction * rel + 0.5 * min_rate) continue;
    }
    Sums& s = sums_[h];
    Quad& blk = block_[h];  // the residuals go into the open block (noise weighting)
    // Direction terms (header): the relative rate's direction is the axis in a segment's frame
    // while the other segment is nearly still.
    const double fd = opt_.direction_fraction;
    const auto add_direction = [&](const Eigen::Vector3d& w_axis, int part) {
      double k;
      Eigen::Vector2d u;
      perp_terms(w_axis, k, u);
      const double wt = w_axis.squaredNorm();
      blk.g.segment<2>(part) += 0.5 * wt * u;
      blk.s += wt * k;
      blk.scale += wt * wt;
    };
    if (fd > 0 && rel > min_rate) {
      if (wp.norm() <= fd * rel) add_direction(w_rel, 2);
      if (wc.norm() <= fd * rel) add_direction((q[p].conjugate() * q[c]) * wc - wp, 0);
    }
    // The rate-norm residual |w_p x j_p|^2 - |w_c x j_c|^2.
    double kp, kc;
    Eigen::Vector2d up, uc;
    perp_terms(wp, kp, up);
    perp_terms(wc, kc, uc);
    const Eigen::Vector4d a(up.x(), up.y(), -uc.x(), -uc.y());
    const double b = kp - kc;
    blk.h.noalias() += a * a.transpose();
    blk.g += a * b;
    blk.s += b * b;
    const double sc = wp.squaredNorm() + wc.squaredNorm();
    blk.scale += sc * sc;
    ++blk.n;
    s.travel_rad += rel * dt_w_s_[c];
    // The parent's rotation about axes other than the hinge axis (y) while the hinge flexes:
    // what pins the parent's yaw.
    if (rel > 2 * min_rate) s.parent_travel_rad += std::hypot(wp.x(), wp.z()) * dt_w_s_[c];
  }
}

void HingeAxisRefiner::close_block(size_t h) {
  Quad& b = block_[h];
  double w = 1;
  if (opt_.noise_weighting) {
    // The block's own noise: its mean squared residual at its own best yaws (two fitted
    // parameters), floored relative to its rate scale.
    const double range = opt_.max_yaw_deg * kDegToRad;
    const YawFit f = fit(b.h, b.g, b.s, range, false, 0, 0, 0, -1);
    const double floor = std::max(opt_.block_noise_floor * b.scale, 1e-300);
    w = std::max(b.n - 2, 1) / std::max(f.cost, floor);
  }
  Sums& s = sums_[h];
  s.h.noalias() += w * b.h;
  s.g += w * b.g;
  s.s += w * b.s;
  s.scale += w * b.scale;
  s.n += b.n;
  b = Quad{};
}

bool HingeAxisRefiner::estimate(int hinge, double ref_yaw_p, double ref_yaw_c, double margin,
                                HingeEstimate& out) const {
  const Sums& s = sums_[hinge];
  out.travel_deg = s.travel_rad * kRadToDeg;
  if (s.n < 10 || s.scale <= 0) return false;
  const double range = opt_.max_yaw_deg * kDegToRad;
  const YawFit f = fit(s.h, s.g, s.s, range, false, 0, ref_yaw_p, ref_yaw_c, margin);
  const double bp = f.yaw_p, bc = f.yaw_c;
  out.parent_yaw_deg = bp * kRadToDeg;
  out.child_yaw_deg = bc * kRadToDeg;
  out.applied_child_yaw_deg = out.child_yaw_deg;
  out.rms_residual = std::sqrt(std::max(f.cost, 0.0) / s.scale);
  out.parent_travel_deg = s.parent_travel_rad * kRadToDeg;
  const double edge = range - 0.5 * kDegToRad;
  const bool ok = out.travel_deg >= opt_.min_travel_deg && std::abs(bc) < edge;
  out.parent_valid =
      ok && std::abs(bp) < edge && s.parent_travel_rad >= opt_.min_parent_off_axis_deg * kDegToRad;
  return ok;
}

HingeAxisRefiner::YawFit HingeAxisRefiner::fit(const Eigen::Matrix4d& h, const Eigen::Vector4d& g,
                                               double s, double range, bool parent_fixed,
                                               double fixed_yaw_p, double ref_yaw_p,
                                               double ref_yaw_c, double basin_margin) {
  // cost(y) = x^T H x + 2 g^T x + s with x = (cos fp, sin fp, cos fc, sin fc), f = 2 (phi + y).
  const auto half = [](double y) {
    const double f = 2 * (kAxisPhi + y);
    return Eigen::Vector2d(std::cos(f), std::sin(f));
  };
  const auto cost = [&](double yp, double yc) {
    Eigen::Vector4d x;
    x << half(yp), half(yc);
    return x.dot(h * x) + 2 * g.dot(x) + s;
  };
  // 1. A 1 deg grid; cost(i, j) = a_i + b_j + v_i . xc_j + s, the terms precomputed per node.
  constexpr int kMaxGrid = 90;
  const int n_grid = std::clamp(static_cast<int>(std::floor(range * kRadToDeg)), 0, kMaxGrid);
  const int n_p = parent_fixed ? 1 : 2 * n_grid + 1, n_c = 2 * n_grid + 1;
  std::array<double, 2 * kMaxGrid + 1> a{}, b{};
  std::array<Eigen::Vector2d, 2 * kMaxGrid + 1> v, xc;
  const auto yaw_p_at = [&](int i) {
    return parent_fixed ? fixed_yaw_p : (i - n_grid) * kDegToRad;
  };
  const auto yaw_c_at = [&](int j) { return (j - n_grid) * kDegToRad; };
  const Eigen::Matrix2d hpp = h.topLeftCorner<2, 2>(), hcc = h.bottomRightCorner<2, 2>();
  const Eigen::Matrix2d hpc = h.topRightCorner<2, 2>();
  for (int i = 0; i < n_p; ++i) {
    const Eigen::Vector2d xp = half(yaw_p_at(i));
    a[i] = xp.dot(hpp * xp) + 2 * g.head<2>().dot(xp);
    v[i] = 2 * hpc.transpose() * xp;
  }
  for (int j = 0; j < n_c; ++j) {
    xc[j] = half(yaw_c_at(j));
    b[j] = xc[j].dot(hcc * xc[j]) + 2 * g.tail<2>().dot(xc[j]);
  }
  const auto grid = [&](int i, int j) { return a[i] + b[j] + v[i].dot(xc[j]) + s; };
  // 2. Its local minima (no neighbour lower), the kMaxBasins lowest of them.
  constexpr int kMaxBasins = 12;
  std::array<YawFit, kMaxBasins> basins;
  int n_basins = 0;
  for (int i = 0; i < n_p; ++i) {
    for (int j = 0; j < n_c; ++j) {
      const double c = grid(i, j);
      bool local_min = true;
      for (int di = -1; di <= 1 && local_min; ++di)
        for (int dj = -1; dj <= 1 && local_min; ++dj) {
          const int ni = i + di, nj = j + dj;
          if ((di || dj) && ni >= 0 && ni < n_p && nj >= 0 && nj < n_c && grid(ni, nj) < c)
            local_min = false;
        }
      if (!local_min) continue;
      int k = std::min(n_basins, kMaxBasins - 1);
      if (n_basins == kMaxBasins && basins[k].cost <= c) continue;
      for (; k > 0 && basins[k - 1].cost > c; --k)
        basins[k] = basins[k - 1];
      basins[k] = {yaw_p_at(i), yaw_c_at(j), c};
      n_basins = std::min(n_basins + 1, kMaxBasins);
    }
  }
  // 3. Damped Newton iterations from each to its exact minimum. The minimum often lies in a long
  // narrow valley (the two yaws are strongly correlated), where a grid node lies up to degrees
  // away along the valley and jumps between nodes as the data change slightly; the iteration is
  // continuous in the data.
  const auto polish = [&](YawFit& m) {
    m.cost = cost(m.yaw_p, m.yaw_c);  // the grid sums the terms in another order
    double lambda = 0;
    for (int it = 0; it < 100; ++it) {
      const double fp = 2 * (kAxisPhi + m.yaw_p), fc = 2 * (kAxisPhi + m.yaw_c);
      Eigen::Vector4d x;
      x << half(m.yaw_p), half(m.yaw_c);
      const Eigen::Vector4d r = h * x + g;
      // dx/dy (x depends on yaw_p through entries 0, 1 and on yaw_c through 2, 3).
      Eigen::Matrix<double, 4, 2> dx = Eigen::Matrix<double, 4, 2>::Zero();
      dx(0, 0) = -2 * std::sin(fp);
      dx(1, 0) = 2 * std::cos(fp);
      dx(2, 1) = -2 * std::sin(fc);
      dx(3, 1) = 2 * std::cos(fc);
      Eigen::Vector2d grad = 2 * dx.transpose() * r;
      Eigen::Matrix2d hess = 2 * dx.transpose() * h * dx;
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
        Eigen::Matrix2d mm = hess;
        mm.diagonal().array() += lambda * diag_scale;
        const Eigen::LDLT<Eigen::Matrix2d> ldlt(mm);
        const Eigen::Vector2d step = -ldlt.solve(grad);
        const auto damp_more = [&] { lambda = lambda == 0 ? 1e-6 : lambda * 8; };
        // Not positive definite (a saddle, or indefinite away from the minimum): damp more.
        if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || !step.allFinite() ||
            step.squaredNorm() == 0) {
          damp_more();
          continue;
        }
        const double np = std::clamp(m.yaw_p + step.x(), -range, range);
        const double nc = std::clamp(m.yaw_c + step.y(), -range, range);
        const double c = cost(np, nc);
        if (c < m.cost) {
          improved = true;
          converged = std::abs(np - m.yaw_p) + std::abs(nc - m.yaw_c) < 1e-10;
          m = {np, nc, c};
          lambda *= 0.25;
        } else {
          damp_more();
        }
      }
      if (!improved || converged) break;
    }
  };
  if (basin_margin < 0) {  // the former search: the grid's lowest node's basin only
    polish(basins[0]);
    return basins[0];
  }
  double lowest = std::numeric_limits<double>::infinity();
  int n_distinct = 0;
  for (int k = 0; k < n_basins; ++k) {
    YawFit m = basins[k];
    polish(m);
    bool duplicate = false;  // several grid minima along one valley reach the same minimum
    for (int q = 0; q < n_distinct && !duplicate; ++q)
      duplicate = std::abs(basins[q].yaw_p - m.yaw_p) + std::abs(basins[q].yaw_c - m.yaw_c) <
                  0.01 * kDegToRad;
    if (duplicate) continue;
    basins[n_distinct++] = m;
    lowest = std::min(lowest, m.cost);
  }
  // 4. Of the minima the data do not separate (cost within basin_margin of the lowest), the one
  // nearest the yaws in use: an offset changes basin only when the data clearly say so.
  YawFit best{parent_fixed ? fixed_yaw_p : 0.0, 0.0, std::numeric_limits<double>::infinity()};
  double best_dist = std::numeric_limits<double>::infinity();
  for (int k = 0; k < n_distinct; ++k) {
    const YawFit& m = basins[k];
    if (!(m.cost <= lowest + basin_margin * std::abs(lowest))) continue;
    const double dist = std::hypot(parent_fixed ? 0.0 : m.yaw_p - ref_yaw_p, m.yaw_c - ref_yaw_c);
    if (dist < best_dist) {
      best_dist = dist;
      best = m;
    }
  }
  return best;
}

bool HingeAxisRefiner::update(int64_t t_ns) {
  if (!opt_.enabled || !started_) return false;
  if (static_cast<double>(t_ns - t_last_update_ns_) * 1e-9 < opt_.update_interval_s) return false;
  t_last_update_ns_ = t_ns;
  // The hysteresis holds a basin once its offset is in use; a pair's first estimate has none to
  // hold (the N-pose value is no fit) and takes the lowest minimum.
  const auto margin = [&](size_t h) {
    return opt_.basin_margin < 0 || applied_[h] ? opt_.basin_margin : 0.0;
  };
  // Close the open blocks (one per update interval; a block with too few samples stays open).
  const int min_block = opt_.noise_weighting ? std::max(opt_.block_min_samples, 3) : 1;
  for (size_t h = 0; h < kRefinePairs.size(); ++h)
    if (block_[h].n >= min_block) close_block(h);
  for (size_t h = 0; h < kRefinePairs.size(); ++h) {
    // Re-estimate only pairs with new data (the search is ~10^4 cost evaluations).
    if (sums_[h].n != n_estimated_[h]) {
      HingeEstimate e;
      e.valid = estimate(static_cast<int>(h), alpha_[index(kRefinePairs[h].parent)],
                         alpha_[index(kRefinePairs[h].child)], margin(h), e);
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
        const Sums& s = sums_[h];
        e.applied_child_yaw_deg =
            fit(s.h, s.g, s.s, range, true, mean, mean, alpha_[c], margin(h)).yaw_c * kRadToDeg;
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
  for (size_t h = 0; h < kRefinePairs.size(); ++h)
    applied_[h] = applied_[h] || est_[h].valid;
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
