// The virtual gyro scale calibration on a table (see table_spin.hpp).
#include "mocap/sim/table_spin.hpp"

#include <cmath>

#include "mocap/core/units.hpp"
#include "mocap/filter/gyro_scale.hpp"
#include "smoothstep.hpp"

namespace mocap::sim {

std::vector<ImuSample> table_spin_samples(SensorErrorModel model, const MagneticFieldParams& field,
                                          double rate_hz, int turns, double extra_deg) {
  std::vector<ImuSample> out;
  const double dt = 1.0 / rate_hz;
  const Eigen::Vector3d b_earth = field.earth_field_uT();
  double t = 0;
  // q(tau) for tau in [0, 1] over `duration_s`, sampled with rates from finite differences.
  const auto play = [&](double duration_s, auto q_at) {
    const int n = static_cast<int>(std::ceil(duration_s * rate_hz));
    for (int k = 0; k < n; ++k) {
      const double u = static_cast<double>(k) / n, u2 = static_cast<double>(k + 1) / n;
      const Eigen::Quaterniond q = q_at(u), q2 = q_at(u2);
      const Eigen::AngleAxisd d(q.conjugate() * q2);  // sensor-frame rotation over dt
      SensorKinematics kin;
      kin.q_earth_sensor = q;
      kin.w_sensor_rad_s = d.axis() * d.angle() / dt;
      ImuSample s;
      model.measure(kin, b_earth, dt, s);
      s.sensor_id = 0;
      s.t_host_ns = s.t_device_ns = static_cast<int64_t>(std::llround(t * 1e9));
      out.push_back(s);
      t += dt;
    }
  };
  // Each axis up in turn: the rotation that takes the sensor axis onto the earth's z.
  const Eigen::Quaterniond up[3] = {
      Eigen::Quaterniond(Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitY())),
      Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX())),
      Eigen::Quaterniond::Identity()};
  double heading = 0;
  for (int ax = 0; ax < 3; ++ax) {
    const Eigen::Quaterniond base = up[ax];
    const auto at = [&](double yaw) {
      return Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ())) * base;
    };
    play(2.0, [&](double) { return at(heading); });
    const double total = (360.0 * turns + extra_deg) * kRadPerDeg;
    const double h0 = heading;
    play(total / (200 * kRadPerDeg) * 1.9,
         [&](double u) { return at(h0 + total * smoothstep5(u)); });
    heading = h0 + total;
    play(2.0, [&](double) { return at(heading); });
    if (ax < 2) {  // a 90 deg flip onto the next axis
      const Eigen::Quaterniond from = at(heading);
      const Eigen::Quaterniond to =
          Eigen::Quaterniond(Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ())) * up[ax + 1];
      play(1.0, [&](double u) { return from.slerp(smoothstep5(u), to); });
    }
  }
  return out;
}

Eigen::Vector3d calibrated_gyro_scale(const SensorErrorModel& model, double rate_hz) {
  return estimate_gyro_scale(table_spin_samples(model, MagneticFieldParams{}, rate_hz)).scale();
}

}  // namespace mocap::sim
