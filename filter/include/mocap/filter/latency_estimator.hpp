// Online estimate of how much later than the gyro a vector sensor samples the motion, from
// the vector itself: a sensor that lags by L reads x(t) = Exp(w L) x_now(t), so in a frame
// where the true vector is constant its fast deviations are L v, v = the frame's image of
// (w x x). Plain data.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace mocap {

/// Least squares of the high-passed x on the high-passed v (both normalised by |x|),
/// exponentially weighted. latency_s() shrinks towards 0 while the rotation excitation
/// (RMS of the high-passed v) is below min_rate_rad_s.
struct LatencyEstimator {
  Eigen::Vector3d x_mean = Eigen::Vector3d::Zero(), v_mean = Eigen::Vector3d::Zero();
  double sxv = 0, svv = 0;  ///< weighted sums (rad/s) and (rad/s)^2
  bool init = false;

  /// x_f: the vector in a frame where it should be constant; v_f: (w x x) in that frame.
  /// k_hp: first-order gain of the high-pass (mean removal); k_avg: of the averaging.
  void step(const Eigen::Vector3d& x_f, const Eigen::Vector3d& v_f, double k_hp, double k_avg) {
    const double n2 = x_f.squaredNorm();
    if (!(n2 > 0)) return;
    const double inv = 1.0 / std::sqrt(n2);
    const Eigen::Vector3d x = x_f * inv, v = v_f * inv;
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
    const double l = sxv / std::max(svv, min_rate_rad_s * min_rate_rad_s);
    return std::clamp(l, -max_s, max_s);
  }
};

}  // namespace mocap
