// The dataset README's full-body metric: rotations since t_ref, one fitted world rotation G.
#include "mocap/sim/segment_metric.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

#include "mocap/core/units.hpp"

namespace mocap::sim {
namespace {

double angle_deg(const Eigen::Quaterniond& q) {
  return 2 * std::acos(std::min(1.0, std::abs(q.normalized().w()))) * kDegPerRad;
}

}  // namespace

void SegmentMetric::add(const Orientations& q_est, const Orientations& q_true) {
  if (est_.empty()) {
    ref_est_ = q_est;
    ref_true_ = q_true;
  }
  Orientations d_est, d_true;
  for (int s = 0; s < kSegmentCount; ++s) {
    d_est[s] = (q_est[s] * ref_est_[s].conjugate()).normalized();
    d_true[s] = (q_true[s] * ref_true_[s].conjugate()).normalized();
  }
  est_.push_back(d_est);
  true_.push_back(d_true);
}

SegmentMetric::Result SegmentMetric::result(const Eigen::Quaterniond* g_given) const {
  Result r;
  r.frames = frames();
  if (est_.empty()) return r;
  // G D_true G^-1 rotates D_true's vector part by G: fit G to map the true vector parts onto the
  // estimated ones (Kabsch, sign fixed by w >= 0), the least-squares chordal fit.
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (size_t k = 0; k < est_.size(); ++k)
    for (int s = 0; s < kSegmentCount; ++s) {
      if (!scored_[s]) continue;
      const Eigen::Quaterniond& e = est_[k][s];
      const Eigen::Quaterniond& t = true_[k][s];
      const Eigen::Vector3d ve = e.w() < 0 ? Eigen::Vector3d(-e.vec()) : Eigen::Vector3d(e.vec());
      const Eigen::Vector3d vt = t.w() < 0 ? Eigen::Vector3d(-t.vec()) : Eigen::Vector3d(t.vec());
      h += ve * vt.transpose();
    }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) d(2, 2) = -1;
  const Eigen::Matrix3d rot = svd.matrixU() * d * svd.matrixV().transpose();
  r.g = h.squaredNorm() > 0 ? Eigen::Quaterniond(rot).normalized() : Eigen::Quaterniond::Identity();
  if (g_given) r.g = *g_given;
  int n = 0;
  double sum = 0;
  for (int s = 0; s < kSegmentCount; ++s) {
    if (!scored_[s]) continue;
    double sq = 0;
    for (size_t k = 0; k < est_.size(); ++k) {
      const Eigen::Quaterniond mapped = r.g * true_[k][s] * r.g.conjugate();
      const double e = angle_deg(est_[k][s] * mapped.conjugate());
      sq += e * e;
    }
    r.segment_rms_deg[s] = std::sqrt(sq / static_cast<double>(est_.size()));
    sum += r.segment_rms_deg[s];
    ++n;
  }
  r.mean_deg = n ? sum / n : 0;
  return r;
}

}  // namespace mocap::sim
