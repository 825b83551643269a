// HingeHeading: a knee's relative heading held to its hinge (see hinge_heading.hpp).
#include "mocap/rig/hinge_heading.hpp"

#include <algorithm>
#include <cmath>

#include "mocap/core/units.hpp"
#include "mocap/skeleton/quat_math.hpp"

namespace mocap::rig {

void HingeHeading::add(const Eigen::Vector3d& y1, const Eigen::Vector3d& y2, double dt_s,
                       bool refuse_far) {
  if (!(dt_s > 0) || dt_s > 0.1) return;
  if (!y1.allFinite() || !y2.allFinite()) return;
  const double h1 = std::hypot(y1.x(), y1.y()), h2 = std::hypot(y2.x(), y2.y());
  const double weight = std::min(h1, h2) * std::min(h1, h2);
  if (weight < 1e-3) return;
  // The yaw taking the lower axis' horizontal direction onto the upper's.
  const double error_rad = wrap_angle_rad(heading_of_rad(y1) - heading_of_rad(y2));
  if (refuse_far && std::abs(error_rad) > opt_.max_error_deg * kRadPerDeg) {
    ++refused_;
    return;
  }
  const double tau_s = followed_s_ < opt_.start_s ? opt_.start_tau_s : opt_.tau_s;
  pending_.add(weight * error_rad * std::min(dt_s / tau_s, 1.0));
  followed_s_ += weight * dt_s;
}

int HingeHeading::take_refused() {
  const int n = refused_;
  refused_ = 0;
  return n;
}

void HingeHeading::reset() {
  pending_.reset();
  refused_ = 0;
  followed_s_ = 0;
}

}  // namespace mocap::rig
