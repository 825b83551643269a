// Holding a sensor's heading on the gyro while its magnetometer is disturbed (heading_hold.hpp).
#include "mocap/skeleton/heading_hold.hpp"

#include <cmath>

#include "mocap/skeleton/quat_math.hpp"

namespace mocap {

Eigen::Quaterniond HeadingHold::update(const Eigen::Quaterniond& q9, const Eigen::Quaterniond& q6,
                                       bool mag_disturbed, int64_t t_ns) {
  if (!opt_.enabled) return q9;
  // The filter's 9-D output is its 6-D one turned about the vertical: the offset is that yaw.
  const Eigen::Vector3d x9 = q9 * Eigen::Vector3d::UnitX(), x6 = q6 * Eigen::Vector3d::UnitX();
  const double meas = std::atan2(x9.y(), x9.x()) - std::atan2(x6.y(), x6.x());
  if (!std::isfinite(meas)) return q9;
  if (!started_) {
    started_ = true;
    offset_rad_ = std::remainder(meas, 2 * M_PI);
  } else if (!mag_disturbed) {
    const double dt = std::max(0.0, static_cast<double>(t_ns - t_last_ns_) * 1e-9);
    const double max_step = opt_.slew_deg_s * kDegToRad * std::min(dt, 0.1);
    const double err = std::remainder(meas - offset_rad_, 2 * M_PI);
    offset_rad_ = std::remainder(offset_rad_ + std::clamp(err, -max_step, max_step), 2 * M_PI);
  }
  holding_ = mag_disturbed;
  t_last_ns_ = t_ns;
  return (yaw_rotation(offset_rad_) * q6).normalized();
}

}  // namespace mocap
