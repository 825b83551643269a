// The attitude filter's evolving state (FilterState): one small plain struct per stage, so a
// filter can be saved and restored (AttitudeFilter::state() / set_state()) as plain data.
// Stages and equations: docs/filter.md.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>

#include "mocap/filter/hard_iron_estimator.hpp"
#include "mocap/filter/latency_estimator.hpp"
#include "mocap/filter/lowpass.hpp"

namespace mocap {

/// One input stream's timing (gyro, acc or mag each track their own period).
struct StreamTiming {
  bool have = false;    ///< a sample of this stream was accepted
  int64_t t_ns = 0;     ///< its timestamp
  double ts_nom_s = 0;  ///< tracked sampling period (0 until the second sample)
  int long_run = 0;     ///< consecutive intervals over 5 nominal periods (three re-set it)
};

/// Strapdown integration of the gyro.
struct StrapdownState {
  Eigen::Quaterniond q_gyr = Eigen::Quaterniond::Identity();  ///< sensor -> almost-inertial
  Eigen::Vector3d last_gyr_rad_s = Eigen::Vector3d::Zero();   ///< newest gyro sample
};

/// Inclination.
struct InclinationState {
  Eigen::Quaterniond q_acc = Eigen::Quaterniond::Identity();  ///< almost-inertial -> 6D earth
  Lowpass<3> acc_lp;                                          ///< acc, almost-inertial frame
  Eigen::Vector3d last_acc_earth = Eigen::Vector3d::UnitZ();  ///< its direction, 6D earth
};

/// Heading (Kalman, scalar about earth z).
struct HeadingState {
  double delta_rad = 0;                                         ///< heading offset 6D earth -> ENU
  Eigen::Quaterniond q_delta = Eigen::Quaterniond::Identity();  ///< rotation by delta_rad
  double delta_var_rad2 = 10;                                   ///< heading variance
  double k_init = 1.0;  ///< start-up gain schedule (0 once over)
  bool set = false;     ///< the first field sample set the provisional heading
  Eigen::Vector3d last_m_e = Eigen::Vector3d::Zero();  ///< newest field, 6D frame
};

/// Gyro bias Kalman filter, fed once per block of acc samples (about 100 Hz).
struct BiasState {
  Eigen::Vector3d rad_s = Eigen::Vector3d::Zero();  ///< the estimate
  Eigen::Matrix3d p = Eigen::Matrix3d::Zero();      ///< its covariance, in (0.01 deg/s)^2
  bool p_init = false;
  bool rest_seen = false;  ///< the first rest's mean was taken (start-up over)
  int n = 0;               ///< acc samples in this block
  Eigen::Vector2d corr_sum = Eigen::Vector2d::Zero();  ///< horizontal corrections summed
  Lowpass<9> motion_r_lp;                              ///< low-passed rotation matrix
  Lowpass<2> motion_bias_lp;                           ///< low-passed applied bias
};

/// Gyro gain G (row-major 3x3, the gyro reads (I + G) w + b) and its Kalman filter.
struct GyroGainState {
  Eigen::Matrix<double, 9, 1> g = Eigen::Matrix<double, 9, 1>::Zero();
  Eigen::Matrix<double, 9, 9> p = Eigen::Matrix<double, 9, 9>::Zero();  ///< in gain^2
  bool p_init = false;
  int n = 0;                                                ///< bias steps since the last update
  Eigen::Vector3d gyr_sum_rad_s = Eigen::Vector3d::Zero();  ///< gyro summed over a bias block
  Lowpass<18> reg_lp;  ///< low-pass of the regressor R_ri w_j, rows 0 and 1 of R
  Eigen::Matrix<double, 2, 9> reg = Eigen::Matrix<double, 2, 9>::Zero();      ///< its output
  Eigen::Matrix<double, 2, 9> reg_sum = Eigen::Matrix<double, 2, 9>::Zero();  ///< block sum
  int reg_n = 0;

  /// G as a matrix (scale on the diagonal, misalignment off it).
  Eigen::Matrix3d matrix() const {
    return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(g.data());
  }
};

/// Rest detection.
struct RestState {
  bool at_rest = false;
  double t_s = 0;                     ///< time the deviations have stayed below the thresholds
  double dev_gyr2 = 0, dev_acc2 = 0;  ///< squared deviations from the low-passes
  Lowpass<3> gyr_lp, acc_lp;
  Eigen::Vector3d last_gyr_lp = Eigen::Vector3d::Zero();  ///< rad/s, low-passed gyro
  /// Until the first rest: the gyro summed over the acc samples of the current rest candidate.
  Eigen::Vector3d gyr_sum_rad_s = Eigen::Vector3d::Zero();
  int n = 0;
};

/// Magnetic disturbance: reference field, candidate for a new one, rejection budget.
struct MagDisturbanceState {
  bool disturbed = true;
  bool have_ref = false;             ///< a reference field was accepted (start-up is over)
  double ref_norm = 0, ref_dip = 0;  ///< reference field, uT and rad (6D frame)
  double ref_head_rad = 0;           ///< reference of the heading innovation (its slow part)
  double undisturbed_t_s = 0, reject_t_s = 0;
  double cand_norm = -1, cand_dip = 0, cand_t_s = 0;  ///< candidate reference
  double cand_age_s = 0;     ///< time the field has stayed consistent with the candidate
  double cand_head_rad = 0;  ///< the candidate's heading against the gyro-propagated heading
  Lowpass<2> norm_dip_lp;
  double norm_dip[2] = {0, 0};  ///< smoothed field norm (uT) and dip (rad), 6D frame
  double head_dev_rad = 0;      ///< smoothed heading innovation (the field's heading - estimate)
  bool head_settled = false;    ///< the heading test applies (update_mag_disturbance)
};

/// Hard-iron offset: the estimator and the choice of what it subtracts.
struct HardIronState {
  HardIronEstimator est;
  int n = 0;          ///< magnetometer samples since the last estimator step
  double dt_s = 0;    ///< and their time
  double select = 0;  ///< low-passed score difference without / with the offset
  double weight = 0;  ///< weight of the offset applied (0..1)
  Eigen::Vector3d applied_uT = Eigen::Vector3d::Zero();  ///< offset subtracted (sensor frame)
};

/// Upset recovery: the check after a clipped gyro sample.
struct UpsetState {
  bool checking = false;
  double since_s = 0;   ///< time since the last clipped sample
  double hold_t_s = 0;  ///< time the current verdict (disagree / agree) has held
  bool disagree = false;
  /// The fresh orientation (almost-inertial -> ENU) when the disagreement began to hold.
  Eigen::Quaterniond q_hold = Eigen::Quaterniond::Identity();
  Lowpass<3> acc_lp, mag_lp;  ///< fast low-passes, almost-inertial frame, since that sample
  double mag_t_s = 0;         ///< field time in mag_lp
  /// The bias estimate and covariance before the first clipped sample of this upset.
  Eigen::Vector3d bias_before_rad_s = Eigen::Vector3d::Zero();
  Eigen::Matrix3d bias_p_before = Eigen::Matrix3d::Zero();
  bool bias_p_init_before = false;
};

/// Everything that evolves; can be saved and restored (plain data).
struct FilterState {
  StreamTiming gyr_timing, acc_timing, mag_timing;
  StrapdownState strapdown;
  InclinationState inclination;
  HeadingState heading;
  BiasState bias;
  GyroGainState gyr_gain;
  RestState rest;
  MagDisturbanceState mag_dist;
  HardIronState hard_iron;
  LatencyEstimator mag_latency;
  UpsetState upset;
};

}  // namespace mocap
