// HingeAxisEstimator: a hinge's axis in both sensors' frames from their inclinations (see
// hinge_axis.hpp).
#include "mocap/rig/hinge_axis.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>

#include "mocap/core/units.hpp"

namespace mocap::rig {
namespace {

/// Noise floor of the elevation residual u.j (inclination error of a filter, ~0.6 deg).
constexpr double kResidualFloor = 0.01;
/// Residuals (soft tissue, the joint's own play) stay correlated about this long.
constexpr double kCorrelationS = 0.5;
// One axis flipped alone must fit this many times worse than the fit for the fit to fix the
// axes' relative sign.
constexpr double kRelativeSignRatio = 4.0;

/// Smallest curvature of j^T s j across the unit vector j (the flattest way to turn it).
double least_curvature(const Eigen::Matrix3d& s, const Eigen::Vector3d& j) {
  const Eigen::Vector3d a =
      std::abs(j.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d u = j.cross(a).normalized(), v = j.cross(u);
  Eigen::Matrix2d t;
  t << u.dot(s * u), u.dot(s * v), v.dot(s * u), v.dot(s * v);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(t);
  return std::max(es.eigenvalues()[0], 0.0);
}

}  // namespace

HingeAxisEstimator::HingeAxisEstimator(int flex_sign, int capacity)
    : flex_sign_(flex_sign >= 0 ? 1 : -1),
      ring_(static_cast<size_t>(std::max(capacity, 16))),
      windows_(static_cast<size_t>(std::ceil(kForgetS / kWindowS))) {}

void HingeAxisEstimator::reset(int64_t t_ns) {
  head_ = count_ = 0;
  full_evidence_ = false;
  t0_ns_ = t_prev_ns_ = t_entry_ns_ = t_solve_ns_ = t_window_ns_ = t_ns;
  for (Window& w : windows_)
    w = Window{};
  window_head_ = 0;
  i1_.setZero();
  i2_.setZero();
  normal_.setZero();
  prior_.setZero();
  d_rad_ = 0;
  relative_sign_known_ = false;
  sum_.setZero();
  weight_ = 0;
  known_ = updated_ = rows_on_ = false;
  j1_ = j2_ = Eigen::Vector3d::UnitY();
  sigma_deg_ = 180;
  sign_agreement_ = 0;
}

void HingeAxisEstimator::set_pose_up(const Eigen::Vector3d& up1, const Eigen::Vector3d& up2) {
  prior_.setZero();
  if (!(up1.norm() > 0.5 && up2.norm() > 0.5)) return;  // (NaN fails too)
  const Eigen::Vector3d u1 = up1.normalized(), u2 = up2.normalized();
  prior_.block<3, 3>(0, 0) = kPriorSamples * u1 * u1.transpose();
  prior_.block<3, 3>(3, 3) = kPriorSamples * u2 * u2.transpose();
}

void HingeAxisEstimator::add(const Eigen::Quaterniond& q1, const Eigen::Quaterniond& q2,
                             const Eigen::Vector3d& w1, const Eigen::Vector3d& w2, int64_t t_ns) {
  if (t0_ns_ == 0 || t_ns <= t_prev_ns_ || !w1.allFinite() || !w2.allFinite() ||
      !q1.coeffs().allFinite() || !q2.coeffs().allFinite())
    return;
  const double dt_s = std::min(static_cast<double>(t_ns - t_prev_ns_) * 1e-9, 0.1);
  t_prev_ns_ = t_ns;
  i1_ += w1 * dt_s;
  i2_ += w2 * dt_s;
  const double since_s = static_cast<double>(t_ns - t_entry_ns_) * 1e-9;
  if (since_s < kSampleEveryS) return;
  t_entry_ns_ = t_ns;
  // The elevation constraint's normal matrix, forgotten over kForgetS.
  Eigen::Matrix<double, 6, 1> v;
  v << q1.normalized().conjugate() * Eigen::Vector3d::UnitZ(),
      -(q2.normalized().conjugate() * Eigen::Vector3d::UnitZ());
  const double keep = std::exp(-since_s / kForgetS);
  normal_ = keep * normal_ + v * v.transpose();
  sum_ = keep * sum_ + v;
  weight_ = keep * weight_ + 1;
  // The horizontal rows, x and y of q1 j1 - Rz(d) q2 j2, in the current window.
  if (static_cast<double>(t_ns - t_window_ns_) * 1e-9 >= kWindowS) {
    t_window_ns_ = t_ns;
    window_head_ = (window_head_ + 1) % static_cast<int>(windows_.size());
    windows_[static_cast<size_t>(window_head_)] = Window{};
  }
  {
    Window& w = windows_[static_cast<size_t>(window_head_)];
    const Eigen::Matrix3d r1 = q1.normalized().toRotationMatrix(),
                          r2 = q2.normalized().toRotationMatrix();
    const Eigen::Vector3d x1 = r1.row(0), y1 = r1.row(1), x2 = r2.row(0), y2 = r2.row(1);
    w.a += x1 * x1.transpose() + y1 * y1.transpose();
    w.b += x2 * x2.transpose() + y2 * y2.transpose();
    w.cc += x1 * x2.transpose() + y1 * y2.transpose();
    w.cs += y1 * x2.transpose() - x1 * y2.transpose();
    ++w.n;
  }
  // The joint angle's integrals while either segment turns (for the signs).
  if (w1.norm() > 0.3 || w2.norm() > 0.3) {
    ring_[static_cast<size_t>(head_)] = Entry{i1_, i2_};
    head_ = (head_ + 1) % static_cast<int>(ring_.size());
    count_ = std::min(count_ + 1, static_cast<int>(ring_.size()));
  }
  if (static_cast<double>(t_ns - t_solve_ns_) * 1e-9 < kSolveEveryS) return;
  t_solve_ns_ = t_ns;
  solve();
}

bool HingeAxisEstimator::updated() {
  const bool u = updated_;
  updated_ = false;
  return u;
}

void HingeAxisEstimator::solve() {
  if (weight_ < 1) return;
  // Enough tilt: the up axes' spread in both frames.
  const Eigen::Matrix<double, 6, 1> mean = sum_ / weight_;
  const Eigen::Matrix<double, 6, 6> cov = normal_ - weight_ * mean * mean.transpose();
  const double evidence = std::min(cov.block<3, 3>(0, 0).trace(), cov.block<3, 3>(3, 3).trace());
  if (evidence < kEarlyEvidence * 0.5) return;
  full_evidence_ = evidence >= kMinEvidence * 0.5;
  // The axes and the windows' relative headings, alternated (horizontal_rows fits the headings
  // to the axes as they are) kFitRounds times from the last answer.
  Eigen::Matrix<double, 6, 6> whole;
  Eigen::Vector3d j1, j2;
  const Eigen::Vector3d j1_last = j1_, j2_last = j2_;
  for (int round = 0; round < kFitRounds; ++round) {
    whole = normal_ + horizontal_rows() + prior_;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> es(whole);
    const Eigen::Matrix<double, 6, 1> x = es.eigenvectors().col(0);
    const double n1 = x.head<3>().norm(), n2 = x.tail<3>().norm();
    if (n1 < 0.3 || n2 < 0.3) {  // one segment alone explains it: not a hinge's axis
      j1_ = j1_last;
      j2_ = j2_last;
      return;
    }
    // The eigenvector's sign is arbitrary: the axes keep theirs.
    const double sign = x.head<3>().dot(j1_) < 0 ? -1.0 : 1.0;
    j1 = sign * x.head<3>() / n1;
    j2 = sign * x.tail<3>() / n2;
    j1_ = j1;
    j2_ = j2;
  }
  // Residual per sample and the flattest curvature across each axis.
  Eigen::Matrix<double, 6, 1> xs;
  xs << j1, j2;
  const double residual2 = std::max(xs.dot(whole * xs), 0.0) / weight_;
  const double k1 = least_curvature(whole.block<3, 3>(0, 0) / weight_, j1);
  const double k2 = least_curvature(whole.block<3, 3>(3, 3) / weight_, j2);
  // Samples a correlation time apart count as independent.
  const double independent = std::max(1.0, weight_ * kSampleEveryS / kCorrelationS);
  const double var = residual2 + kResidualFloor * kResidualFloor;
  sigma_deg_ = std::min(
      180.0, std::sqrt(var / (std::max(std::min(k1, k2), 1e-12) * independent)) * kDegPerRad);
  // The fit fixes the axes' relative sign where the axis' elevation varied: one axis flipped
  // alone then fits clearly worse. Where it stayed level it fits as well, and only the
  // flexing side can tell.
  xs.head<3>() = -j1;
  // From the elevation rows alone: the horizontal rows were taken with a relative heading that
  // holds for the axes' relative sign at the time, so they would keep a wrong one.
  const double flipped2 = std::max(xs.dot(normal_ * xs), 0.0) / weight_;
  xs.head<3>() = j1;
  const double elevation2 = std::max(xs.dot(normal_ * xs), 0.0) / weight_;
  constexpr double kFloor2 = kResidualFloor * kResidualFloor;
  if (elevation2 > kRelativeSignRatio * (flipped2 + kFloor2)) j2_ = -j2_;  // the rows' sign lost
  relative_sign_known_ = std::max(flipped2, elevation2) >
                         kRelativeSignRatio * (std::min(flipped2, elevation2) + kFloor2);
  choose_signs(relative_sign_known_);
  known_ = updated_ = true;
  rows_on_ = rows_on_ || (signs_sure() && full_evidence_);
}

Eigen::Matrix<double, 6, 6> HingeAxisEstimator::horizontal_rows() {
  Eigen::Matrix<double, 6, 6> h = Eigen::Matrix<double, 6, 6>::Zero();
  // The rows need the axes' relative sign, and axes as sure as the tracker takes (rows fitted
  // to a first rough answer kept the axes near it for seconds).
  if (!known_ || !relative_sign_known_ || !rows_on_) return h;
  const int n = static_cast<int>(windows_.size());
  for (int k = 1; k <= n; ++k) {  // oldest first: d_rad_ ends as the newest window's
    const Window& w = windows_[static_cast<size_t>((window_head_ + k) % n)];
    if (w.n == 0) continue;
    const double c = j1_.dot(w.cc * j2_), s = j1_.dot(w.cs * j2_);
    if (std::hypot(c, s) < 1e-9) continue;  // both axes vertical throughout: no heading in it
    d_rad_ = std::atan2(s, c);
    const Eigen::Matrix3d m = std::cos(d_rad_) * w.cc + std::sin(d_rad_) * w.cs;
    h.block<3, 3>(0, 0) += w.a;
    h.block<3, 3>(0, 3) -= m;
    h.block<3, 3>(3, 0) -= m.transpose();
    h.block<3, 3>(3, 3) += w.b;
  }
  return h;
}

void HingeAxisEstimator::choose_signs(bool relative_sign_known) {
  // The pair of signs whose joint angle since the straight calibration pose stays on the
  // flexing side in most recent samples (both flipped together only, where the fit fixed the
  // relative sign).
  const double lo = -kOvershootDeg * kRadPerDeg, hi = kMaxFlexDeg * kRadPerDeg;
  std::array<int, 4> on_side{};
  const std::array<std::array<double, 2>, 4> signs = {{{1, 1}, {1, -1}, {-1, 1}, {-1, -1}}};
  for (int k = 0; k < count_; ++k) {
    const Entry& e = ring_[static_cast<size_t>(k)];
    const double a1 = e.i1.dot(j1_), a2 = e.i2.dot(j2_);
    for (size_t c = 0; c < 4; ++c) {
      if (relative_sign_known && signs[c][0] != signs[c][1]) continue;
      const double theta = flex_sign_ * (signs[c][1] * a2 - signs[c][0] * a1);
      on_side[c] += theta >= lo && theta <= hi;
    }
  }
  const size_t best =
      static_cast<size_t>(std::max_element(on_side.begin(), on_side.end()) - on_side.begin());
  j1_ *= signs[best][0];
  j2_ *= signs[best][1];
  int second = 0;  // the runner-up among the pairs considered
  for (size_t c = 0; c < 4; ++c)
    if (c != best && !(relative_sign_known && signs[c][0] != signs[c][1]))
      second = std::max(second, on_side[c]);
  sign_agreement_ = static_cast<double>(on_side[best]) / std::max(count_, 1);
  sign_margin_ = static_cast<double>(on_side[best] - second) / std::max(count_, 1);
}

}  // namespace mocap::rig
