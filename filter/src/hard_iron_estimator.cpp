// HardIronEstimator: 6-state Kalman filter for (earth field, sensor-fixed offset), gated by
// the offset's own covariance. Equations in docs/filter.md ("Hard-iron offset").
#include "mocap/filter/hard_iron_estimator.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace mocap {

// Joint prior around the current offset: b ~ (b, p0 F^2 I); c = R (m - b) inherits b's
// uncertainty (perfectly anti-correlated) plus the measurement noise.
void HardIronEstimator::restart(const Eigen::Vector3d& m_uT, const Eigen::Matrix3d& r_es,
                                const HardIronCoeffs& k) {
  if (!b_uT.allFinite()) b_uT.setZero();
  if (!(f_uT > 0)) f_uT = std::max((m_uT - b_uT).norm(), 1e-6);
  const double f2 = f_uT * f_uT;
  const double pb = k.p0_offset_rel2 * f2;
  c_uT = r_es * (m_uT - b_uT);
  p.setZero();
  p.topLeftCorner<3, 3>().diagonal().setConstant(pb + k.r_rel2 * f2);
  p.bottomRightCorner<3, 3>().diagonal().setConstant(pb);
  p.topRightCorner<3, 3>() = -pb * r_es;
  p.bottomLeftCorner<3, 3>() = -pb * r_es.transpose();
  nis = 1;
}

void HardIronEstimator::step(const Eigen::Vector3d& m_uT, const Eigen::Matrix3d& r_es, double dt_s,
                             double f_ref_uT, const HardIronCoeffs& k) {
  if (f_ref_uT > 0) f_uT = f_ref_uT;
  // gate() has solved the offset block's eigenproblem for this P when it ran (the eigenvalues
  // are the same with or without eigenvectors): only the other paths solve it here.
  if (update(m_uT, r_es, dt_s, k)) return;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
  es.computeDirect(p.bottomRightCorner<3, 3>(), Eigen::EigenvaluesOnly);
  offset_sigma_uT = std::sqrt(std::max(es.eigenvalues()(2), 0.0));
}

bool HardIronEstimator::update(const Eigen::Vector3d& m_uT, const Eigen::Matrix3d& r_es,
                               double dt_s, const HardIronCoeffs& k) {
  if (!init) {
    init = true;
    restart(m_uT, r_es, k);
    return false;
  }
  const double f2 = f_uT * f_uT;
  // Predict: the field in the 6D frame wanders with its heading drift; b may change slowly.
  p.topLeftCorner<3, 3>().diagonal().array() += k.q_field_rel2_s * f2 * dt_s;
  for (int i = 3; i < 6; ++i)
    if (p(i, i) < k.p0_offset_rel2 * f2) p(i, i) += k.q_offset_rel2_s * f2 * dt_s;
  // Measurement m = R^T c + b: H = [R^T I], so P H^T = P_left R + P_right.
  const Eigen::Vector3d y = m_uT - r_es.transpose() * c_uT - b_uT;
  const Eigen::Matrix<double, 6, 3> pht = p.leftCols<3>() * r_es + p.rightCols<3>();
  Eigen::Matrix3d s = r_es.transpose() * pht.topRows<3>() + pht.bottomRows<3>();
  s.diagonal().array() += k.r_rel2 * f2;
  const Eigen::Matrix3d s_inv = s.inverse();
  const double nis_now = y.dot(s_inv * y) / 3.0;
  if (!std::isfinite(nis_now)) {
    restart(m_uT, r_es, k);
    return false;
  }
  nis += k.k_nis * (std::min(nis_now, 100.0) - nis);
  if (nis > k.nis_max) {
    // The data no longer fit a constant field plus a constant offset (a magnet was attached
    // or removed, or the field is inhomogeneous): forget b's certainty and fit again.
    ++restarts;
    restart(m_uT, r_es, k);
    gate(k);
    return true;
  }
  const Eigen::Matrix<double, 6, 3> gain = pht * s_inv;
  c_uT += gain.topRows<3>() * y;
  b_uT += gain.bottomRows<3>() * y;
  p -= gain * pht.transpose();
  p = 0.5 * (p + p.transpose()).eval();
  gate(k);
  return true;
}

// Use b only along directions whose variance is below the gate, and only when it is larger
// and more significant than the smallest offset worth applying.
void HardIronEstimator::gate(const HardIronCoeffs& k) {
  const double g2 = k.gate_rel2 * f_uT * f_uT;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
  es.computeDirect(p.bottomRightCorner<3, 3>());
  offset_sigma_uT = std::sqrt(std::max(es.eigenvalues()(2), 0.0));
  Eigen::Vector3d u = Eigen::Vector3d::Zero();
  double z2 = 0;  // squared significance of the used part (offset / its sigma)
  double lam_used = 0;
  for (int i = 0; i < 3; ++i) {
    const double lam = std::max(es.eigenvalues()(i), 1e-12);
    const double w = lam < g2 ? 1.0 : 0.0;  // all or nothing: a partial offset is a bias
    const Eigen::Vector3d v = es.eigenvectors().col(i);
    const double bv = v.dot(b_uT);
    u += w * bv * v;
    z2 += w * bv * bv / lam;
    lam_used = std::max(lam_used, w * lam);
  }
  // Offsets below min_offset x F, or below min_sigmas standard deviations, are not applied;
  // each condition ramps to full over a factor 2 (x F) or one more sigma (a ramp, not a
  // shrink: a large offset must be removed completely).
  const double n = u.norm(), min_n = k.min_offset_rel * f_uT;
  const double w_size = std::clamp(n / std::max(min_n, 1e-12) - 1.0, 0.0, 1.0);
  const double w_sig = std::clamp(std::sqrt(z2) - k.min_sigmas, 0.0, 1.0);
  used_uT = u * (w_size * w_sig);
  used_sigma_uT = w_size * w_sig > 0 ? std::sqrt(lam_used) : 0.0;
  if (!used_uT.allFinite()) {
    used_uT.setZero();
    used_sigma_uT = 0;
  }
}

}  // namespace mocap
