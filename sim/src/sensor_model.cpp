// Virtual IMU error model, magnetic field and sensor mounting (see sensor_model.hpp).
#include "mocap/sim/sensor_model.hpp"
#include "mocap/core/units.hpp"
#include "mocap/skeleton/sensor_sites.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace mocap::sim {
namespace {}

SensorModelParams SensorModelParams::ideal() {
  SensorModelParams p;
  p.gyr_noise_density_dps_rthz = p.gyr_bias_sigma_dps = p.gyr_bias_walk_dps_rts = 0;
  p.gyr_scale_sigma = 0;
  p.acc_noise_density_m_s2_rthz = p.acc_bias_sigma_m_s2 = p.acc_scale_sigma = 0;
  p.mag_noise_uT = p.mag_hard_iron_sigma_uT = p.mag_scale_sigma = 0;
  p.mount_misalignment_deg = 0;
  p.jitter_sigma_s = 0;
  p.drop_probability = 0;
  return p;
}

Eigen::Vector3d MagneticFieldParams::earth_field_uT() const {
  const double inc = inclination_deg * kRadPerDeg, dec = declination_deg * kRadPerDeg;
  const double h = total_uT * std::cos(inc);
  return {h * std::sin(dec), h * std::cos(dec), -total_uT * std::sin(inc)};
}

Eigen::Vector3d MagneticFieldParams::field_uT(const Eigen::Vector3d& p, double t_s,
                                              const TruthFrame* body) const {
  Eigen::Vector3d b = earth_field_uT();
  for (const MagneticDipole& d : dipoles) {
    if (t_s < d.t_begin_s || t_s >= d.t_end_s) continue;
    Eigen::Vector3d p_dipole = d.p_earth_m, moment = d.moment_A_m2;
    if (d.carried_by_segment >= 0) {
      if (!body) continue;
      const Eigen::Quaterniond& q = body->q_earth_segment[d.carried_by_segment];
      p_dipole = body->p_earth_segment_m[d.carried_by_segment] + q * d.p_earth_m;
      moment = q * d.moment_A_m2;
    }
    const Eigen::Vector3d r = p - p_dipole;
    const double n = std::max(r.norm(), 0.02);  // inside the magnet: cap the field
    const Eigen::Vector3d u = r / std::max(r.norm(), 1e-9);
    // mu0/(4 pi) = 1e-7 T m/A = 0.1 uT m/A.
    b += 0.1 * (3 * u * u.dot(moment) - moment) / (n * n * n);
  }
  return b;
}

bool MagneticFieldParams::time_varying() const {
  for (const MagneticDipole& d : dipoles)
    if (d.carried_by_segment >= 0 || d.t_begin_s > -1e300 || d.t_end_s < 1e300) return true;
  return false;
}

std::vector<MagneticDipole> disturbance_preset(std::string_view name, double height_m,
                                               double t_begin_s) {
  const double s = height_m / 1.75;
  // A neodymium magnet (1 A m^2) beside the right thigh, near the hanging right hand and forearm.
  const MagneticDipole magnet{{0.05 * s, -0.33 * s, 0.80 * s}, {0.0, 0.7, 0.7}};
  // Steel desk frame in front of the performer: induced dipole below the reach zone.
  const MagneticDipole desk{{0.55 * s, 0.0, 0.70 * s}, {0.0, 1.5, -4.0}};
  if (name == "none") return {};
  if (name == "magnet") return {magnet};
  if (name == "desk") return {desk};
  if (name == "both") return {magnet, desk};
  if (name == "arm_magnet") {
    // Held against the right forearm, 10 cm from its sensor's site (halfway down the forearm,
    // outer side), for 6 s: a phone or a tool's magnet near one arm.
    MagneticDipole held;
    held.carried_by_segment = index(Segment::forearm_r);
    held.p_earth_m = Eigen::Vector3d(0.0, -0.10 * s, -0.08 * s);
    held.moment_A_m2 = Eigen::Vector3d(0.2, 0.2, 0.0);
    held.t_begin_s = t_begin_s;
    held.t_end_s = t_begin_s + 6.0;
    return {held};
  }
  throw std::invalid_argument("unknown magnetic disturbance '" + std::string(name) +
                              "' (valid: none, magnet, desk, both)");
}

SensorMount make_mount(Segment seg, const BodyDimensions& dims, const SensorModelParams& p,
                       std::mt19937_64& rng) {
  using V = Eigen::Vector3d;
  const V r = standard_site_position_m(seg, dims);
  const V normal = standard_site_normal_body(seg);
  // Sensor z along the outward normal, then the strap roll about it, then misalignment.
  Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(V::UnitZ(), normal);
  std::uniform_real_distribution<double> roll(-std::numbers::pi, std::numbers::pi);
  std::normal_distribution<double> tilt(0.0, p.mount_misalignment_deg * kRadPerDeg);
  const double roll_rad = roll(rng);  // drawn always so the stream does not depend on flags
  // The pelvis sensor sits on a belt clip with a fixed roll (its x axis up), so its -z axis points
  // forward: the calibration's heading reference. Other straps have any roll.
  // (FromTwoVectors already turns the sensor's x up for the -x normal.)
  if (seg != Segment::pelvis && p.random_mount_roll)
    q = q * Eigen::AngleAxisd(roll_rad, V::UnitZ());
  const V mis(tilt(rng), tilt(rng), tilt(rng));
  if (mis.norm() > 0) q = q * Eigen::AngleAxisd(mis.norm(), mis.normalized());
  if (p.random_mount_orientation) {
    // Uniform over rotations (normalised 4D Gaussian), from a stream of its own so that the
    // other draws do not change.
    std::mt19937_64 copy = rng;  // a copy: the shared stream does not advance
    std::mt19937_64 any(copy() ^ (0x9E3779B97F4A7C15ull * static_cast<uint64_t>(index(seg) + 1)));
    std::normal_distribution<double> n(0, 1);
    q = Eigen::Quaterniond(n(any), n(any), n(any), n(any));
  }
  return {seg, r, q.normalized()};
}

SensorErrorModel::SensorErrorModel(const SensorModelParams& p, double rate_hz, uint64_t seed)
    : p_(p), rng_(seed) {
  gyr_sigma_rad_s_ = p.gyr_noise_density_dps_rthz * kRadPerDeg * std::sqrt(rate_hz);
  acc_sigma_m_s2_ = p.acc_noise_density_m_s2_rthz * std::sqrt(rate_hz);
  gyr_bias_rad_s_ = noise3(p.gyr_bias_sigma_dps * kRadPerDeg);
  gyr_scale_ = Eigen::Vector3d::Ones() + noise3(p.gyr_scale_sigma);
  acc_bias_m_s2_ = noise3(p.acc_bias_sigma_m_s2);
  acc_scale_ = Eigen::Vector3d::Ones() + noise3(p.acc_scale_sigma);
  mag_offset_uT_ = noise3(p.mag_hard_iron_sigma_uT);
  mag_scale_ = Eigen::Vector3d::Ones() + noise3(p.mag_scale_sigma);
}

Eigen::Vector3d SensorErrorModel::noise3(double sigma) {
  const double x = normal_(rng_), y = normal_(rng_), z = normal_(rng_);
  return Eigen::Vector3d(x, y, z) * sigma;
}

void SensorErrorModel::measure(const SensorKinematics& k, const Eigen::Vector3d& b_earth_uT,
                               double dt_s, ImuSample& out) {
  const Eigen::Quaterniond q_sensor_earth = k.q_earth_sensor.conjugate();
  const Eigen::Vector3d f_earth = k.a_earth_m_s2 + Eigen::Vector3d(0, 0, p_.gravity_m_s2);
  out.gyr_rad_s =
      gyr_scale_.cwiseProduct(k.w_sensor_rad_s) + gyr_bias_rad_s_ + noise3(gyr_sigma_rad_s_);
  out.acc_m_s2 =
      acc_scale_.cwiseProduct(q_sensor_earth * f_earth) + acc_bias_m_s2_ + noise3(acc_sigma_m_s2_);
  out.mag_uT = mag_scale_.cwiseProduct(q_sensor_earth * b_earth_uT) + mag_offset_uT_ +
               noise3(p_.mag_noise_uT);
  gyr_bias_rad_s_ += noise3(p_.gyr_bias_walk_dps_rts * kRadPerDeg * std::sqrt(std::max(dt_s, 0.0)));
  const double gyr_max = p_.gyr_range_dps * kRadPerDeg;
  bool saturated = false, gyr_clipped = false;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(out.gyr_rad_s[i]) > gyr_max) {
      out.gyr_rad_s[i] = std::copysign(gyr_max, out.gyr_rad_s[i]);
      saturated = gyr_clipped = true;
    }
    if (std::abs(out.acc_m_s2[i]) > p_.acc_range_m_s2) {
      out.acc_m_s2[i] = std::copysign(p_.acc_range_m_s2, out.acc_m_s2[i]);
      saturated = true;
    }
  }
  out.valid = kFieldGyr | kFieldAcc | kFieldMag;
  out.flags =
      kFlagSynthetic | (saturated ? kFlagSaturated : 0) | (gyr_clipped ? kFlagGyrClipped : 0);
}

}  // namespace mocap::sim
