// Relative magnetometer heading smoothing (see relative_mag_heading.hpp).
#include "mocap/skeleton/relative_mag_heading.hpp"

#include <algorithm>
#include <cmath>

#include "mocap/skeleton/quat_math.hpp"

namespace mocap {

RelativeMagHeading::RelativeMagHeading(RigMapping rig, RelativeMagHeadingOptions options)
    : opt_(options) {
  for (int i = 0; i < kSegmentCount && ref_ < 0; ++i)
    if (rig.tracked(i)) ref_ = i;
  reset();
}

void RelativeMagHeading::reset() {
  have_ref_ = false;
  have_.fill(false);
  lp_rad_.fill(0.0);
  turn_rad_.fill(0.0);
  correction_rad_.fill(0.0);
  t_ns_.fill(0);
  q_prev_.fill(Eigen::Quaterniond::Identity());
}

Eigen::Quaterniond RelativeMagHeading::apply(int segment, const Eigen::Quaterniond& q, int64_t t_ns,
                                             double mag_heading_rad) {
  if (!opt_.enabled || segment < 0 || segment >= kSegmentCount) return q;
  if (!std::isfinite(mag_heading_rad)) {
    if (segment == ref_) {
      have_ref_ = false;
      have_.fill(false);
    }
    have_[segment] = false;
    correction_rad_[segment] = 0;
    return q;
  }
  if (segment == ref_) {
    if (!have_ref_) have_.fill(false);  // the others restart from the reference's new start
    ref_rad_ = mag_heading_rad;
    have_ref_ = true;
    return q;
  }
  if (!have_ref_) return q;
  const Eigen::Quaterniond q_gyro = yaw_rotation(-mag_heading_rad) * q;
  const double rel = mag_heading_rad - ref_rad_;
  double& lp = lp_rad_[segment];
  if (!have_[segment]) {
    have_[segment] = true;
    lp = rel;
  } else {
    const double dt_s = static_cast<double>(std::max<int64_t>(t_ns - t_ns_[segment], 0)) * 1e-9;
    // The gyros' rotation about the earth vertical since the last sample (the turn budget; the
    // magnetometer's own heading steps do not count).
    const Eigen::AngleAxisd step((q_gyro * q_prev_[segment].conjugate()).normalized());
    const double turn = std::abs(step.angle() * step.axis().z());
    double& budget = turn_rad_[segment];
    budget = budget * std::exp(-dt_s / opt_.turn_memory_s) + turn;
    const bool calibrated = opt_.gyro_scale_calibrated[segment] && opt_.gyro_scale_calibrated[ref_];
    const double turning = calibrated ? 0.0 : std::min(1.0, budget / (opt_.turn_deg * kDegToRad));
    const double k = std::min(1.0, dt_s / opt_.tau_s + turning * dt_s / opt_.turn_tau_s);
    lp += k * std::remainder(rel - lp, 2 * M_PI);
  }
  t_ns_[segment] = t_ns;
  q_prev_[segment] = q_gyro;
  correction_rad_[segment] = std::remainder(lp - rel, 2 * M_PI);
  return (yaw_rotation(correction_rad_[segment]) * q).normalized();
}

}  // namespace mocap
