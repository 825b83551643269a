// RangeHeading: a ball joint's range of motion holds its child's 6D heading (see
// range_heading.hpp).
#include "mocap/rig/range_heading.hpp"

#include <algorithm>
#include <cmath>

#include "mocap/core/units.hpp"
#include "mocap/skeleton/quat_math.hpp"

namespace mocap::rig {

void RangeHeading::add(const JointLimit& limit, const Eigen::Quaterniond& q_earth_parent,
                       const Eigen::Quaterniond& q_earth_child, double dt_s) {
  if (!(dt_s > 0) || dt_s > 0.1 || !limit.limited || limit.hinge) return;
  Eigen::Quaterniond allowed;
  const JointCheck now = check_joint(limit, q_earth_parent.conjugate() * q_earth_child, &allowed);
  if (!now.violated || !(now.violation_deg > opt_.margin_deg)) return;
  // The yaw (twist about the earth's vertical) of the turn from the nearest allowed child
  // orientation onto the actual one.
  const Eigen::Quaterniond d = q_earth_child * (q_earth_parent * allowed).conjugate();
  const double yaw_rad = wrap_angle_rad(2 * std::atan2(d.z(), d.w()));
  // Only a heading error a turn about the vertical mends: turned back by it, the joint must
  // come at least half of that turn nearer its range.
  const JointCheck turned =
      check_joint(limit, q_earth_parent.conjugate() * yaw_rotation(-yaw_rad) * q_earth_child);
  if (!(turned.violation_deg < now.violation_deg - 0.5 * std::abs(yaw_rad) * kDegPerRad)) return;
  // Back to the margin, not to the range: a real joint may reach beyond the table's range.
  const double share = (now.violation_deg - opt_.margin_deg) / now.violation_deg;
  pending_.add(-share * yaw_rad * std::min(dt_s / opt_.tau_s, 1.0));
}

}  // namespace mocap::rig
