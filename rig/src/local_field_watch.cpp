// LocalFieldWatch: a suspected local field at the calibration, held and re-checked (see
// local_field_watch.hpp).
#include "mocap/rig/local_field_watch.hpp"

#include <algorithm>
#include <cmath>

#include "mocap/core/units.hpp"
#include "mocap/skeleton/quat_math.hpp"

namespace mocap::rig {
namespace {

/// The filter's heading offset: q_earth_sensor = Rz(this) q_earth_sensor_6d.
double filter_heading_rad(const FilterOutput& o) {
  return yaw_of_rad(o.q_earth_sensor * o.q_earth_sensor_6d.conjugate());
}

/// The field's heading in the 6D frame, as the filter measures it (from north, +y).
double field_heading_rad(const Eigen::Vector3d& m) {
  return std::atan2(m.x(), m.y());
}

}  // namespace

void LocalFieldWatch::suspect(double turn_rad, const FilterOutput& o, double norm_th) {
  if (!(o.mag_6d_uT.squaredNorm() > 0) || !std::isfinite(turn_rad)) return;
  state_ = State::suspect;
  hold_rad_ = filter_heading_rad(o);
  m0_uT_ = o.mag_6d_uT;
  turn_rad_ = turn_rad;
  t_s_ = 0;
  lp_rad_ = 0;
  norm_th_ = norm_th;
}

bool LocalFieldWatch::on_field(const FilterOutput& o, double dt_s, double& turned_rad) {
  if (state_ == State::idle) return false;
  const Eigen::Vector3d& m = o.mag_6d_uT;
  const double n = m.norm(), n0 = m0_uT_.norm();
  const double turned = wrap_angle_rad(field_heading_rad(m) - field_heading_rad(m0_uT_));
  const double gain = std::clamp(dt_s / kStepS, 0.0, 1.0);
  const double step = wrap_angle_rad(turned - lp_rad_);
  lp_rad_ = wrap_angle_rad(lp_rad_ + gain * step);
  const bool same_norm = n > 0 && std::abs(n - n0) <= norm_th_ * n0;
  if (state_ == State::follow) {
    // Confirmed: the held heading follows the field's further turn (low-passed) until the
    // filter's own heading has caught up.
    if (same_norm) {
      follow_rad_ += gain * wrap_angle_rad(turned - follow_rad_);
      hold_rad_ = wrap_angle_rad(suspect_hold_rad_ + follow_rad_);
    }
    return false;
  }
  t_s_ += dt_s;
  // About the suspected turn in all, at least half of it within the last few seconds.
  const bool as_suspected = same_norm &&
                            std::abs(wrap_angle_rad(turned - turn_rad_)) <=
                                std::max(5.0 * kRadPerDeg, 0.35 * std::abs(turn_rad_)) &&
                            step * turn_rad_ >= 0.5 * turn_rad_ * turn_rad_;
  if (!as_suspected) {
    if (t_s_ > kHoldS) state_ = State::idle;
    return false;
  }
  state_ = State::follow;
  suspect_hold_rad_ = hold_rad_;
  follow_rad_ = turned;
  hold_rad_ = wrap_angle_rad(hold_rad_ + turned);
  t_s_ = 0;
  turned_rad = turned;
  return true;
}

void LocalFieldWatch::on_sample(const FilterOutput& o, double dt_s) {
  if (state_ != State::follow) return;
  t_s_ += dt_s;
  if (std::abs(wrap_angle_rad(filter_heading_rad(o) - hold_rad_)) <= kReleaseDeg * kRadPerDeg ||
      t_s_ > kFollowS) {
    state_ = State::idle;
  }
}

Eigen::Quaterniond LocalFieldWatch::q_earth_sensor(const FilterOutput& o) const {
  if (state_ == State::idle) return o.q_earth_sensor;
  return (yaw_rotation(hold_rad_) * o.q_earth_sensor_6d).normalized();
}

}  // namespace mocap::rig
