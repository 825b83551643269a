// Online estimate of how much later than the gyro a vector sensor (acc or mag) samples the
// motion, from the vector itself: a sensor that lags by L reads x(t) = Exp(w L) x_now(t), so
// in the almost-inertial frame (gyro only) its fast deviations are L (w_I x x_I). Plain data.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>

namespace mocap::filt {

/// Least squares of the high-passed x_I on the high-passed w_I x x_I (both normalised by
/// |x|), exponentially weighted. latency_s() shrinks towards 0 while the rotation excitation
/// is small compared to min_rate_rad_s.
struct LatencyEstimator {
  Eigen::Vector3d x_mean = Eigen::Vector3d::Zero(), v_mean = Eigen::Vector3d::Zero();
  double sxv = 0, svv = 0;  ///< weighted sums (rad/s) and (rad/s)^2
  bool init = false;

  /// x_i: the sensor vector in the almost-inertial frame; w_i: the corrected rate there.
  /// k_hp: first-order gain of the high-pass (mean removal); k_avg: of the averaging.
  void step(const Eigen::Vector3d& x_i, const Eigen::Vector3d& w_i, double k_hp, double k_avg) {
    const double n = x_i.norm();
    if (!(n > 0)) return;
    const Eigen::Vector3d x = x_i / n;
    const Eigen::Vector3d v = w_i.cross(x);
    if (!init) {
      x_mean = x;
      v_mean = v;
      init = true;
      return;
    }
    const Eigen::Vector3d dx = x - x_mean, dv = v - v_mean;
    x_mean += k_hp * dx;
    v_mean += k_hp * dv;
    sxv += k_avg * (dx.dot(dv) - sxv);
    svv += k_avg * (dv.squaredNorm() - svv);
  }

  double latency_s(double min_rate_rad_s, double max_s) const {
    const double l = sxv / (svv + min_rate_rad_s * min_rate_rad_s);
    return std::clamp(l, -max_s, max_s);
  }
};

}  // namespace mocap::filt
