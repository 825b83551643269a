// The virtual IMU: how a consumer MEMS gyro/accelerometer/magnetometer strapped to a body segment
// turns the segment's true motion into a sample. Mounting (off-axis position, orientation with a
// random strap roll and misalignment), gyro noise + bias + bias random walk, accelerometer specific
// force (gravity plus the real linear acceleration at the mount point) with noise, bias and scale
// errors, magnetometer from an earth field with dip plus local dipole disturbances, saturation.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <random>
#include <string_view>
#include <vector>

#include "mocap/core/imu_sample.hpp"
#include "mocap/core/segments.hpp"
#include "mocap/sim/body_pose.hpp"
#include "mocap/skeleton/body_model.hpp"

namespace mocap::sim {

/// Error model parameters. Defaults resemble a consumer 9-axis MEMS part (BMI160/ICM-20948
/// class, factory calibrated, strapped on with an elastic band).
struct SensorModelParams {
  double gyr_noise_density_dps_rthz = 0.01;     ///< white noise, deg/s/sqrt(Hz)
  double gyr_bias_sigma_dps = 0.3;              ///< turn-on bias, per axis, deg/s (1 sigma)
  double gyr_bias_walk_dps_rts = 0.003;         ///< bias random walk, deg/s/sqrt(s)
  double gyr_scale_sigma = 0.005;               ///< per-axis scale error (1 sigma, fraction)
  double gyr_range_dps = 2000;                  ///< full scale
  double acc_noise_density_m_s2_rthz = 0.0015;  ///< ~150 ug/sqrt(Hz)
  double acc_bias_sigma_m_s2 = 0.05;            ///< per axis (1 sigma)
  double acc_scale_sigma = 0.005;
  double acc_range_m_s2 = 16 * 9.80665;  ///< +-16 g
  double mag_noise_uT = 0.3;             ///< per-sample white noise (1 sigma)
  double mag_hard_iron_sigma_uT = 1.0;   ///< residual hard-iron offset after calibration
  double mag_scale_sigma = 0.01;
  double mount_misalignment_deg = 5;  ///< extra random mount tilt per axis (1 sigma)
  bool random_mount_roll = true;      ///< strap roll about the surface normal: uniform
  /// Strapped anyhow: the sensor's orientation on its segment is uniformly random (any
  /// rotation; its site stays the standard one), drawn from a stream of its own.
  bool random_mount_orientation = false;
  double jitter_sigma_s = 2e-4;     ///< sample-time jitter (1 sigma, clamped +-40%)
  double drop_probability = 0.002;  ///< chance each sample is lost in transport
  double gravity_m_s2 = 9.80665;

  /// No noise, bias, scale error, misalignment, jitter or drops (mounting still off-axis).
  static SensorModelParams ideal();
};

/// A magnetic dipole near the performer (a magnet, or the induced field of steel furniture).
struct MagneticDipole {
  /// Position in the earth frame; for a carried dipole, in its segment's frame.
  Eigen::Vector3d p_earth_m = Eigen::Vector3d::Zero();
  /// Moment in the earth frame; for a carried dipole, in its segment's frame.
  Eigen::Vector3d moment_A_m2 = Eigen::Vector3d::Zero();
  /// Present only in [t_begin_s, t_end_s) of the motion's time (default: always).
  double t_begin_s = -1e300, t_end_s = 1e300;
  /// Carried by this segment (a magnet held against a limb), or -1: fixed in the room.
  int carried_by_segment = -1;
};

/// Earth field (ENU) with inclination (dip) and declination, plus local dipoles.
struct MagneticFieldParams {
  double total_uT = 50;
  double inclination_deg = 60;  ///< positive: field points down (northern hemisphere)
  double declination_deg = 0;   ///< magnetic north east of true north (earth y axis)
  std::vector<MagneticDipole> dipoles;

  Eigen::Vector3d earth_field_uT() const;
  /// Total field at a point, earth frame, microtesla, at motion time t_s; `body` (the truth at
  /// t_s) places the carried dipoles (ignored without it).
  Eigen::Vector3d field_uT(const Eigen::Vector3d& p_earth_m, double t_s = 0,
                           const TruthFrame* body = nullptr) const;
  /// A dipole carried by a segment or present for a time only.
  bool time_varying() const;
};

/// Named disturbance sets placed around the performer's start position (pelvis at the origin,
/// facing +x): "none", "magnet" (a strong magnet at the right hip, 15 cm from the hanging right
/// hand), "desk" (a steel desk in front, the induced field of its frame under the reaching hands),
/// "both", "arm_magnet" (a 0.3 A m^2 magnet held 10 cm from the right forearm's sensor, moving
/// with the arm, for 6 s from t_begin_s). Throws std::invalid_argument for other names.
std::vector<MagneticDipole> disturbance_preset(std::string_view name, double height_m,
                                               double t_begin_s = 0);

/// Where and how one sensor is strapped to its segment.
struct SensorMount {
  Segment segment = Segment::pelvis;
  Eigen::Vector3d r_segment_sensor_m = Eigen::Vector3d::Zero();  ///< in the segment frame
  Eigen::Quaterniond q_segment_sensor = Eigen::Quaterniond::Identity();
};

/// Body forward (+x) in the pelvis sensor's frame for the nominal belt mount (before
/// misalignment): what a calibration takes as its heading axis.
inline Eigen::Vector3d pelvis_forward_axis_sensor() {
  return -Eigen::Vector3d::UnitZ();
}

/// The nominal surface point where a sensor goes on each segment (segment frame), scaled to the
/// body, lying flat with its z axis along the standard site's outward normal
/// (skeleton/sensor_sites.hpp); then strap roll and misalignment drawn from `rng`.
SensorMount make_mount(Segment s, const BodyDimensions& dims, const SensorModelParams& p,
                       std::mt19937_64& rng);

/// True motion of the sensor at one instant.
struct SensorKinematics {
  Eigen::Quaterniond q_earth_sensor = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p_earth_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d w_sensor_rad_s = Eigen::Vector3d::Zero();  ///< angular rate, sensor frame
  Eigen::Vector3d a_earth_m_s2 = Eigen::Vector3d::Zero();    ///< linear acceleration of the mount
};

/// One sensor's error state (biases, scale, hard iron) and random stream. Deterministic per seed.
class SensorErrorModel {
 public:
  SensorErrorModel(const SensorModelParams& p, double rate_hz, uint64_t seed);
  /// Turns true kinematics and the true field at the sensor into measured values in `out`
  /// (gyr, acc, mag, valid, saturation flag); advances the bias random walk by dt_s.
  void measure(const SensorKinematics& k, const Eigen::Vector3d& b_earth_uT, double dt_s,
               ImuSample& out);
  /// Normal draw from this sensor's stream (used for timing jitter and drops).
  double gauss() { return normal_(rng_); }
  double uniform() { return uniform_(rng_); }
  const Eigen::Vector3d& gyr_bias_rad_s() const { return gyr_bias_rad_s_; }
  /// The drawn hard-iron residual (sensor frame, uT): truth for filter diagnostics.
  const Eigen::Vector3d& mag_offset_uT() const { return mag_offset_uT_; }
  /// The drawn gyro scale per axis (gyro reads scale * w + bias): truth for calibration tests.
  const Eigen::Vector3d& gyr_scale() const { return gyr_scale_; }

 private:
  Eigen::Vector3d noise3(double sigma);
  SensorModelParams p_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  double gyr_sigma_rad_s_, acc_sigma_m_s2_;
  Eigen::Vector3d gyr_bias_rad_s_, gyr_scale_, acc_bias_m_s2_, acc_scale_, mag_offset_uT_,
      mag_scale_;
};

}  // namespace mocap::sim
