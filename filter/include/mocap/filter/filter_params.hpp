// The attitude filter's tuning (FilterParams): one small struct per stage, each parameter with
// its meaning, unit and default. All rate-independent (time constants in seconds, thresholds in
// physical units); one set for every sensor and rate, the defaults are the tested ones
// (docs/filter.md). The [filter] config keys and --set names bind these members by their
// historical flat names (filter_param_names.cpp: `tau_acc_s`, `bias_clip_deg_s`, ...).
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
  bool rest_est = true;               ///< estimate the bias while at rest
  bool motion_est = true;             ///< estimate horizontal bias from inclination corrections
  double sigma_init_deg_s = 0.5;      ///< deg/s, initial bias uncertainty
  double forgetting_time_s = 100;     ///< s, time for the uncertainty to grow by 0.1 deg/s
  double clip_deg_s = 2.0;            ///< deg/s, largest bias estimate and innovation
  double sigma_motion_deg_s = 0.1;    ///< deg/s, measurement noise of the motion update
  double vertical_forgetting = 1e-4;  ///< -, vertical bias pseudo-measurement weight
  double sigma_rest_deg_s = 0.03;     ///< deg/s, measurement noise of the rest update
};

/// Gyro gain (scale factor and misalignment, ours). The gyro reads (I + G) w + b. The motion
/// bias update's inclination corrections also see G w, which grows with the rotation rate, so
/// a 9-state Kalman filter estimates G from the same corrections (regressor: low-passed R w^T)
/// and the gyro is corrected by it.
struct GyroGainParams {
  double sigma_init = 0.02;        ///< -, prior one-sigma per matrix entry (0 disables)
  double forgetting_time_s = 100;  ///< s, time for the uncertainty to grow by 0.001
  double clip = 0.05;              ///< -, largest estimate per matrix entry
};

/// Rest detection: gyro and acc deviations from their low-pass below thresholds.
struct RestParams {
  double min_t_s = 1.5;       ///< s, rest must hold this long
  double filter_tau_s = 0.5;  ///< s, low-pass for the rest deviations
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
  bool rejection = true;        ///< the disturbance tests, rejection and start-up state
  double current_tau_s = 0.05;  ///< s, smoothing of the field norm and dip
  double ref_tau_s = 20.0;      ///< s, tracking of the reference norm and dip
  double norm_th = 0.1;         ///< -, relative norm deviation counted as disturbed
  double dip_th_deg = 10.0;     ///< deg, dip deviation counted as disturbed
  /// deg, heading deviation counted as disturbed (ours): the field's heading in the 6D frame
  /// against the gyro-propagated heading (smoothed over 0.5 s, its slow part tracked), beyond
  /// three sigma of the heading; once the heading has settled
  double heading_th_deg = 5.0;
  double new_time_s = 20.0;             ///< s, a new consistent field is accepted after this
  double new_first_time_s = 5.0;        ///< s, ... or this for the first field
  double new_min_gyr_deg_s = 20.0;      ///< deg/s, only while rotating at least this fast
  double min_undisturbed_time_s = 0.5;  ///< s, undisturbed this long before it is used
  double max_rejection_time_s = 60.0;   ///< s, longest full rejection
  double rejection_factor = 2.0;        ///< -, gain divisor after that

  /// -, soft trust: the heading measurement variance is multiplied by 1 + score, score =
  /// trust_weight * ((norm dev / norm_th)^2 + (dip dev / dip_th_deg)^2
  /// + (heading dev / heading_th_deg)^2) + (rejection time not yet repaid) / tau_mag_s.
  double trust_weight = 3.0;
};

/// Online hard-iron offset b (ours; a magnet or magnetised part fixed to the sensor), from the
/// gyro-predicted rotation of the field (HardIronEstimator, Kalman filter of the field in the
/// 6D frame and b). Noises and gates are fractions of the field norm F. b is subtracted before
/// the disturbance tests and the heading, only along directions whose one-sigma is below
/// gate x F, shrunk by min_offset x F.
struct HardIronParams {
  /// s, without rotation b's uncertainty grows back to its prior over this time (0 disables
  /// the estimator).
  double tau_s = 1000.0;
  double sigma0 = 1.0;        ///< x F, prior one-sigma of b
  double field_rw_deg = 0.3;  ///< deg/sqrt(s), drift of the field in the 6D frame
  double noise = 0.03;        ///< x F, measurement one-sigma (noise + model)
  double gate = 0.03;         ///< x F, b directions with one-sigma below this are used
  double min_offset = 0.02;   ///< x F, smallest offset applied
  double min_sigmas = 3.0;    ///< sigmas, smallest significance applied
  double nis_tau_s = 2.0;     ///< s, averaging of the innovation consistency
  double nis_max = 9.0;       ///< -, above: model broken, b uncertain again
  double step_s = 0.1;        ///< s, estimator period (decimated)
  /// The offset is applied only while it explains a disturbance: the field's norm/dip
  /// deviation from the reference (squared, relative to the thresholds, as the soft trust) is
  /// compared with and without it, the difference low-passed over select_tau_s (s); the
  /// offset's weight ramps from 0 to 1 as that difference goes from 0 to select_margin (-).
  /// select_margin 0 = always applied once gated.
  double select_tau_s = 1.0;
  double select_margin = 0.2;
  /// ... or while the estimator's innovations have stayed consistent (averaged NIS below
  /// consistent_nis (-), no restart) for consistent_s (s): a residual offset too small to show
  /// in the norm/dip still turns the heading with the orientation. consistent_nis 0 = off.
  double consistent_nis = 0.2;
  double consistent_s = 10.0;
  double consistent_min_sigmas = 0.5;  ///< sigmas, significance required on that path
};

/// Magnetometer latency (ours). A magnetometer often samples the motion later than the gyro
/// (longer integration, internal filters): during fast rotation its heading then lags. The
/// latency is estimated online from the field itself (LatencyEstimator: high-passed over
/// hp_tau_s, averaged over tau_s, shrunk towards 0 below min_rate_deg_s of rotation) and the
/// field is rotated back by w * latency.
struct MagLatencyParams {
  double tau_s = 30.0;           ///< s, averaging of the estimate (0 disables)
  double hp_tau_s = 0.5;         ///< s, high-pass of the field and its rate
  double min_rate_deg_s = 30.0;  ///< deg/s, excitation below which the estimate shrinks
  double max_s = 0.05;           ///< s, largest latency compensated
};

/// Input handling: what is integrated or rejected (counted in FilterCounters).
struct InputParams {
  double max_gap_s = 0.25;      ///< s, longer gaps integrate the gyro only over this span
  double max_gyr_rad_s = 70.0;  ///< rad/s, |gyr| above this is rejected (about 4000 deg/s)
  double max_acc_m_s2 = 500.0;  ///< m/s^2, |acc| above this is rejected (about 50 g)
  double max_mag_uT = 10000.0;  ///< uT, |mag| above this is rejected
};

/// Upset recovery (ours). A gyro axis at full scale (the sample's kFlagGyrClipped, or a rate
/// of at least gyr_deg_s for input without flags) has lost rotation the strapdown cannot know.
/// The slow paths would take many seconds to find it (inclination: tau_acc_s; heading:
/// tau_mag_s, and only after the field, whose dip is seen through the wrong inclination, stops
/// being rejected). So for window_s after a clipped sample a fresh orientation is formed from
/// acc (and the field) low-passed over tau_s in the almost-inertial frame and compared with the
/// filter's. Verdicts, each held for hold_s while the fresh orientation turns less than
/// steady_deg there (a swing's specific force turns; a lost rotation is fixed) and the fast
/// acc's norm is within norm_tol of g: the inclination lost (off by over angle_deg): set to the
/// fresh one; with the inclination confirmed (within confirm_deg) and the field passing its
/// tests, the heading lost (over angle_deg): set to the field's; both confirmed: the check
/// ends. A recovery also returns the bias filter to its state before the clipped sample and
/// forgives the field's rejection time. Without a clipped sample nothing changes; the
/// thresholds are such that checks after every fast motion change nothing on the BROAD trials
/// and no CMU clip for the worse (docs/filter.md).
struct UpsetParams {
  bool enabled = true;
  double gyr_deg_s = 1900;   ///< deg/s, an axis this fast may be clipped (input without flags)
  double tau_s = 0.3;        ///< s, the fast low-passes of acc and field
  double window_s = 10.0;    ///< s, longest check after the last clipped sample
  double angle_deg = 30.0;   ///< deg, smallest disagreement corrected
  double confirm_deg = 5.0;  ///< deg, largest disagreement that confirms
  double steady_deg = 5.0;   ///< deg, largest turn of the fresh orientation over hold_s
  double hold_s = 0.2;       ///< s, a verdict must hold this long
  double norm_tol = 0.1;     ///< -, largest relative deviation of the fast acc's norm from g
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
  InputParams input;
  UpsetParams upset;
};

}  // namespace mocap
