// The attitude filter's coefficients (FilterCoeffs): derived from FilterParams and the tracked
// sampling periods, one small struct per stage; recomputed, never saved (AttitudeFilter's
// refresh_coeffs).
#pragma once

#include "mocap/filter/hard_iron_estimator.hpp"
#include "mocap/filter/lowpass.hpp"

namespace mocap {

/// The sampling periods in use, s (a stream's own once tracked, else another's).
struct PeriodCoeffs {
  double gyr_s = 0, acc_s = 0, mag_s = 0;
};

struct RestCoeffs {
  LowpassCoeffs gyr_lp, acc_lp;
};

struct BiasCoeffs {
  int decim = 1;         ///< the bias KF runs every decim acc samples (about 100 Hz)
  double ts_s = 0;       ///< its period
  LowpassCoeffs lp;      ///< tau_acc low-pass at the bias KF rate
  double p0 = 0, v = 0;  ///< initial variance and growth per step, (0.01 deg/s)^2
  double motion_w = 0, vertical_w = 0, rest_w = 0;  ///< measurement variances
};

struct GyroGainCoeffs {
  int reg_decim = 1;  ///< its regressor is low-passed every reg_decim bias steps
  LowpassCoeffs reg_lp;
  int decim = 1;                ///< the gyro-gain KF runs every decim bias steps (about 10 Hz)
  double p0 = 0, v = 0, w = 0;  ///< initial variance, growth per step, measurement variance
};

struct HeadingCoeffs {
  double k_mag = 0;  ///< first-order gain for tau_mag_s (the rejection backstop's limit)
  double q_rad2_s = 0, r0_rad2 = 0;  ///< Kalman process (per s) and measurement variance
  double inv_tau_mag_s = 0;          ///< 1 / tau_mag_s (multiplied: no division per sample)
};

struct MagDisturbanceCoeffs {
  LowpassCoeffs norm_dip_lp;
  double head_th2_rad2 = 0;                          ///< heading_th_deg squared, rad^2
  double inv_head_th2_rad2 = 0, inv_dip_th_rad = 0;  ///< 1 / that, 1 / dip_th_deg in rad
  double k_head = 0;  ///< first-order gain of the heading innovation's smoothing
  double k_ref = 0;   ///< first-order gain of the reference (and candidate) tracking
};

struct HardIronStageCoeffs {
  HardIronCoeffs est;
  int decim = 1;  ///< the estimator runs every decim magnetometer samples
  double k_select = 0;
};

struct MagLatencyCoeffs {
  double k = 0, k_hp = 0;  ///< first-order gains of the averaging and the high-pass
};

struct FilterCoeffs {
  PeriodCoeffs ts;
  LowpassCoeffs acc_lp;  ///< inclination
  RestCoeffs rest;
  BiasCoeffs bias;
  GyroGainCoeffs gyr_gain;
  HeadingCoeffs heading;
  MagDisturbanceCoeffs mag_dist;
  HardIronStageCoeffs hard_iron;
  MagLatencyCoeffs mag_latency;
  LowpassCoeffs upset_acc_lp, upset_mag_lp;  ///< upset recovery's fast low-passes
  double upset_gyr_rad_s = 0;                ///< upset.gyr_deg_s in rad/s
};

}  // namespace mocap
