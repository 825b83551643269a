// BROAD error metric (ported from the benchmark's description in the dataset README).
#include "mocap/eval/broad_metric.hpp"

#include <algorithm>
#include <cmath>
#include "mocap/core/units.hpp"

namespace mocap {

void attitude_error_angles(const Eigen::Quaterniond& q_est, const Eigen::Quaterniond& q_ref,
                           double& total_rad, double& heading_rad, double& inclination_rad) {
  const Eigen::Quaterniond e = (q_est * q_ref.conjugate()).normalized();
  const double w = std::abs(e.w());
  total_rad = 2.0 * std::acos(std::min(w, 1.0));
  heading_rad = 2.0 * std::atan(std::abs(e.z() / e.w()));
  inclination_rad = 2.0 * std::acos(std::min(std::sqrt(e.w() * e.w() + e.z() * e.z()), 1.0));
}

AttitudeErrors score_trial(const BroadTrial& trial, const std::vector<Eigen::Quaterniond>& est) {
  AttitudeErrors r;
  if (!trial.has_ref) return r;
  double st = 0, sh = 0, si = 0;
  const size_t n = std::min(est.size(), trial.size());
  for (size_t i = 0; i < n; ++i) {
    if (trial.has_movement && !trial.movement[i]) continue;
    const Eigen::Vector4d& rv = trial.ref_wxyz[i];
    if (!rv.allFinite()) continue;
    const Eigen::Quaterniond qr(rv[0], rv[1], rv[2], rv[3]);
    double t, h, inc;
    attitude_error_angles(est[i], qr, t, h, inc);
    st += t * t;
    sh += h * h;
    si += inc * inc;
    ++r.n;
  }
  if (r.n == 0) return r;
  r.total_deg = std::sqrt(st / r.n) * kDegPerRad;
  r.heading_deg = std::sqrt(sh / r.n) * kDegPerRad;
  r.inclination_deg = std::sqrt(si / r.n) * kDegPerRad;
  return r;
}

namespace {
constexpr VqfRef kVqf[] = {
    {"01_", 1.99, 1.89, 0.60}, {"04_", 1.07, 0.73, 0.79}, {"06_", 4.03, 3.95, 0.80},
    {"08_", 3.34, 2.84, 1.76}, {"10_", 1.80, 1.78, 0.30}, {"15_", 2.31, 2.26, 0.47},
    {"21_", 4.08, 3.70, 1.72}, {"24_", 1.55, 1.42, 0.61}, {"26_", 1.75, 1.66, 0.56},
    {"28_", 4.04, 3.86, 1.21}, {"30_", 2.57, 2.25, 1.25}, {"32_", 7.67, 7.65, 0.56},
    {"34_", 3.35, 3.29, 0.65}, {"36_", 2.39, 2.22, 0.88}};
}  // namespace

const VqfRef* vqf_reference(const std::string& trial_name) {
  for (const auto& v : kVqf)
    if (trial_name.rfind(v.prefix, 0) == 0) return &v;
  return nullptr;
}

}  // namespace mocap
