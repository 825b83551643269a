// The attitude filter's tuning (FilterParams): one small struct per stage, each parameter with
// its meaning, unit and default. All rate-independent (time constants in seconds, thresholds in
// physical units); one set for every sensor and rate, the defaults are the tested ones
// (docs/filter.md). Only what real data or a sensor's make asks to set is a parameter (25, as
// VQF); the stages' other numbers are fixed constants (filter_constants.hpp). The [filter] config
// keys and --set names bind these members by their historical flat names (filter_param_names.cpp:
// `tau_acc_s`, `bias_clip_deg_s`, ...).
#pragma once

namespace mocap {

/// Inclination: acc low-passed in the almost-inertial frame.
struct InclinationParams {
  double tau_acc_s = 3.0;  ///< s, low-pass time constant of acc (also the bias and gain paths')
};

/// Heading: a scalar Kalman filter of the rotation about earth z from the magnetometer.
struct HeadingParams {
  double tau_mag_s = 9.0;  ///< s, nominal heading time constant in an undisturbed field
  /// deg, steady-state one-sigma heading uncertainty in an undisturbed field (sets the process
  /// and measurement noise together with tau_mag_s).
  double sigma_deg = 1.0;
};

/// Gyro bias: a 3-state Kalman filter (sigma values in deg/s), at rest and in motion.
struct BiasParams {
  bool rest_est = true;             ///< estimate the bias while at rest
  bool motion_est = true;           ///< estimate horizontal bias from inclination corrections
  double forgetting_time_s = 100;   ///< s, time for the uncertainty to grow by 0.1 deg/s
  double clip_deg_s = 2.0;          ///< deg/s, largest bias estimate and innovation
  double sigma_motion_deg_s = 0.1;  ///< deg/s, measurement noise of the motion update
  double sigma_rest_deg_s = 0.03;   ///< deg/s, measurement noise of the rest update
};

/// Gyro gain (scale factor and misalignment, ours). The gyro reads (I + G) w + b. The motion
/// bias update's inclination corrections also see G w, which grows with the rotation rate, so
/// a 9-state Kalman filter estimates G from the same corrections (regressor: low-passed R w^T)
/// and the gyro is corrected by it.
struct GyroGainParams {
  double sigma_init = 0.02;  ///< -, prior one-sigma per matrix entry (0 disables)
};

/// Rest detection: gyro and acc deviations from their low-pass below thresholds.
struct RestParams {
  double min_t_s = 1.5;       ///< s, rest must hold this long
  double th_gyr_deg_s = 2.0;  ///< deg/s, largest gyro deviation at rest
  double th_acc_m_s2 = 0.5;   ///< m/s^2, largest acc deviation at rest
};

/// Magnetic disturbance: the field's norm and dip against a slowly tracked reference, the
/// rejection of a disturbed field and the soft trust of an undisturbed one. Unlike VQF, the
/// first field is accepted at rest too (start-up stand-still = clean reference, full rejection
/// budget for the session). Before it the heading follows the field provisionally (flag
/// mag_no_reference); when it is accepted the start-up gain schedule (K >= 1/N for tau_mag_s)
/// restarts from the provisional heading's variance, counting only samples that pass the tests.
struct MagDisturbanceParams {
  bool rejection = true;     ///< the disturbance tests, rejection and start-up state
  double ref_tau_s = 20.0;   ///< s, tracking of the reference norm and dip
  double norm_th = 0.1;      ///< -, relative norm deviation counted as disturbed
  double dip_th_deg = 10.0;  ///< deg, dip deviation counted as disturbed
  /// deg, heading deviation counted as disturbed (ours): the field's heading in the 6D frame
  /// against the gyro-propagated heading (smoothed over 0.5 s, its slow part tracked), beyond
  /// three sigma of the heading; once the heading has settled
  double heading_th_deg = 5.0;
  double new_time_s = 20.0;  ///< s, a new consistent field is accepted after this

  /// -, soft trust: the heading measurement variance is multiplied by 1 + score, score =
  /// trust_weight * ((norm dev / norm_th)^2 + (dip dev / dip_th_deg)^2
  /// + (heading dev / heading_th_deg)^2) + (rejection time not yet repaid) / tau_mag_s.
  double trust_weight = 3.0;
};

/// Online hard-iron offset b (ours; a magnet or magnetised part fixed to the sensor), from the
/// gyro-predicted rotation of the field (HardIronEstimator, Kalman filter of the field in the
/// 6D frame and b). b is subtracted before the disturbance tests and the heading, only along
/// directions whose one-sigma is below gate x F (F the field norm), and only while it
/// explains a norm/dip deviation (the estimator's noises and the selection:
/// filter_constants.hpp).
struct HardIronParams {
  /// s, without rotation b's uncertainty grows back to its prior over this time (0 disables
  /// the estimator).
  double tau_s = 1000.0;
  double gate = 0.03;  ///< x F, b directions with one-sigma below this are used
};

/// Magnetometer latency (ours). A magnetometer often samples the motion later than the gyro
/// (longer integration, internal filters): during fast rotation its heading then lags. The
/// latency is estimated online from the field itself (LatencyEstimator, high-passed and
/// shrunk towards 0 without rotation: filter_constants.hpp) and the field is rotated back by
/// w * latency.
struct MagLatencyParams {
  double tau_s = 30.0;  ///< s, averaging of the estimate (0 disables)
};

/// Upset recovery (ours). A gyro axis at full scale (the sample's kFlagGyrClipped, or a rate
/// of at least gyr_deg_s for input without flags) has lost rotation the strapdown cannot know.
/// The slow paths would take many seconds to find it (inclination: tau_acc_s; heading:
/// tau_mag_s, and only after the field, whose dip is seen through the wrong inclination, stops
/// being rejected). So for a while after a clipped sample a fresh orientation is formed from
/// acc (and the field) low-passed in the almost-inertial frame and compared with the filter's;
/// a steady, large disagreement sets the inclination, then the heading (the thresholds:
/// filter_constants.hpp; docs/filter.md). A recovery also returns the bias filter to its state
/// before the clipped sample and forgives the field's rejection time. Without a clipped sample
/// nothing changes; checks after every fast motion change nothing on the BROAD trials and no
/// CMU clip for the worse (docs/filter.md).
struct UpsetParams {
  bool enabled = true;
  double gyr_deg_s = 1900;  ///< deg/s, an axis this fast may be clipped (input without flags)
};

/// Every parameter of AttitudeFilter, by stage.
struct FilterParams {
  InclinationParams inclination;
  HeadingParams heading;
  BiasParams bias;
  GyroGainParams gyr_gain;
  RestParams rest;
  MagDisturbanceParams mag_dist;
  HardIronParams hard_iron;
  MagLatencyParams mag_latency;
  UpsetParams upset;
};

}  // namespace mocap
