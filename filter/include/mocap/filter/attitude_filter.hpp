// The per-sensor attitude filter: gyro strapdown + inclination from low-passed acc in an
// almost-inertial frame + magnetometer heading as a separate scalar, with online gyro-bias
// estimation, rest detection and magnetic-disturbance rejection (VQF structure, extended).
// See docs/filter.md for the equations, parameters and measured accuracy.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>

#include "mocap/core/imu_sample.hpp"
#include "mocap/filter/hard_iron_estimator.hpp"
#include "mocap/filter/latency_estimator.hpp"
#include "mocap/filter/lowpass.hpp"

namespace mocap {

/// Tuning, all rate-independent (time constants in seconds, thresholds in physical units).
/// One parameter set for every sensor and rate; the defaults are the tested ones.
struct FilterParams {
  // --- inclination and heading ---
  double tau_acc_s = 3.0;  ///< low-pass of acc in the almost-inertial frame (inclination)
  double tau_mag_s = 9.0;  ///< nominal heading time constant in an undisturbed field
  /// Kalman heading: steady-state one-sigma heading uncertainty in an undisturbed field (sets
  /// the process and measurement noise together with tau_mag_s).
  double heading_sigma_deg = 1.0;
  // --- gyro bias (Kalman filter, sigma values in deg/s) ---
  bool rest_bias_est = true;             ///< estimate bias while at rest
  bool motion_bias_est = true;           ///< estimate horizontal bias from inclination corrections
  double bias_sigma_init_deg_s = 0.5;    ///< initial bias uncertainty
  double bias_forgetting_time_s = 100;   ///< time for the uncertainty to grow by 0.1 deg/s
  double bias_clip_deg_s = 2.0;          ///< largest bias estimate and innovation
  double bias_sigma_motion_deg_s = 0.1;  ///< measurement noise of the motion update
  double bias_vertical_forgetting = 1e-4;  ///< vertical bias pseudo-measurement weight
  double bias_sigma_rest_deg_s = 0.03;     ///< measurement noise of the rest update
  // --- gyro gain (scale factor and misalignment, ours) ---
  /// The gyro reads (I + G) w + b. The motion bias update's inclination corrections also see
  /// G w, which grows with the rotation rate, so a 9-state Kalman filter estimates G from
  /// the same corrections (regressor: low-passed R w^T) and the gyro is corrected by it.
  /// gyr_gain_sigma_init is the prior one-sigma per matrix entry (0 disables).
  double gyr_gain_sigma_init = 0.02;
  double gyr_gain_forgetting_time_s = 100;  ///< time for the uncertainty to grow by 0.001
  double gyr_gain_clip = 0.05;              ///< largest estimate per matrix entry
  // --- rest detection ---
  double rest_min_t_s = 1.5;       ///< rest must hold this long
  double rest_filter_tau_s = 0.5;  ///< low-pass for the rest deviations
  double rest_th_gyr_deg_s = 2.0;  ///< largest gyro deviation at rest
  double rest_th_acc_m_s2 = 0.5;   ///< largest acc deviation at rest
  // --- magnetic disturbance ---
  bool mag_dist_rejection = true;
  double mag_current_tau_s = 0.05;      ///< smoothing of the field norm and dip
  double mag_ref_tau_s = 20.0;          ///< tracking of the reference norm and dip
  double mag_norm_th = 0.1;             ///< relative norm deviation counted as disturbed
  double mag_dip_th_deg = 10.0;         ///< dip deviation counted as disturbed
  double mag_new_time_s = 20.0;         ///< a new consistent field is accepted after this
  double mag_new_first_time_s = 5.0;    ///< ... or this for the first field
  double mag_new_min_gyr_deg_s = 20.0;  ///< only while rotating at least this fast
  // Unlike VQF, the first field is accepted at rest too (start-up stand-still = clean
  // reference, full rejection budget for the session). Before it the heading follows the field
  // provisionally (flag mag_no_reference); when it is accepted the start-up gain schedule
  // (K >= 1/N for tau_mag_s) restarts from the provisional heading's variance, counting only
  // samples that pass the disturbance tests.
  double mag_min_undisturbed_time_s = 0.5;
  double mag_max_rejection_time_s = 60.0;  ///< longest full rejection
  double mag_rejection_factor = 2.0;       ///< gain divisor after that
  /// Soft trust: the heading measurement variance is multiplied by 1 + score, score =
  /// mag_trust_weight * ((norm dev / mag_norm_th)^2 + (dip dev / mag_dip_th_deg)^2)
  /// + (rejection time not yet repaid) / tau_mag_s.
  double mag_trust_weight = 3.0;
  // --- extensions beyond VQF (false/0 = plain VQF behaviour) ---
  /// Online hard-iron offset b (a magnet or magnetised part fixed to the sensor), from the
  /// gyro-predicted rotation of the field (filt::HardIronEstimator, Kalman filter of the
  /// field in the 6D frame and b). hard_iron_tau_s: without rotation b's uncertainty grows
  /// back to its prior over this time (0 disables the estimator). Noises and gates are
  /// fractions of the field norm F. b is subtracted before the disturbance tests and the
  /// heading, only along directions whose one-sigma is below hard_iron_gate x F, shrunk by
  /// hard_iron_min_offset x F.
  double hard_iron_tau_s = 1000.0;
  double hard_iron_sigma0 = 1.0;        ///< prior one-sigma of b, x F
  double hard_iron_field_rw_deg = 0.3;  ///< drift of the field in the 6D frame, deg/sqrt(s)
  double hard_iron_noise = 0.03;        ///< measurement one-sigma (noise + model), x F
  double hard_iron_gate = 0.03;         ///< b directions with one-sigma below this x F used
  double hard_iron_min_offset = 0.02;   ///< smallest offset applied, x F
  double hard_iron_min_sigmas = 3.0;    ///< smallest significance applied, sigmas
  double hard_iron_nis_tau_s = 2.0;     ///< averaging of the innovation consistency
  double hard_iron_nis_max = 9.0;       ///< above: model broken, b uncertain again
  double hard_iron_step_s = 0.1;        ///< estimator period (decimated)
  /// The offset is applied only while it explains a disturbance: the field's norm/dip
  /// deviation from the reference (squared, relative to the thresholds, as the soft trust)
  /// is compared with and without it, the difference low-passed over hard_iron_select_tau_s;
  /// the offset's weight ramps from 0 to 1 as that difference goes from 0 to
  /// hard_iron_select_margin. 0 = always applied once gated.
  double hard_iron_select_tau_s = 1.0;
  double hard_iron_select_margin = 0.2;
  /// ... or while the estimator's innovations have stayed consistent (averaged NIS below
  /// hard_iron_consistent_nis, no restart) for hard_iron_consistent_s: a residual offset too
  /// small to show in the norm/dip still turns the heading with the orientation. 0 = off.
  double hard_iron_consistent_nis = 0.2;
  double hard_iron_consistent_s = 10.0;
  double hard_iron_consistent_min_sigmas = 0.5;  ///< significance required on that path
  // --- magnetometer latency (ours) ---
  /// A magnetometer often samples the motion later than the gyro (longer integration,
  /// internal filters): during fast rotation its heading then lags. The latency is
  /// estimated online from the field itself (filt::LatencyEstimator: high-passed over
  /// mag_latency_hp_tau_s, averaged over mag_latency_tau_s, shrunk towards 0 below
  /// mag_latency_min_rate_deg_s of rotation) and the field is rotated back by w * latency.
  /// mag_latency_tau_s = 0 disables.
  double mag_latency_tau_s = 30.0;
  double mag_latency_hp_tau_s = 0.5;
  double mag_latency_min_rate_deg_s = 30.0;
  double mag_latency_max_s = 0.05;  ///< largest latency compensated
  // --- input handling ---
  double max_gap_s = 0.25;      ///< longer gaps integrate the gyro only over this span
  double max_gyr_rad_s = 70.0;  ///< |gyr| above this is rejected (about 4000 deg/s)
  double max_acc_m_s2 = 500.0;  ///< |acc| above this is rejected (about 50 g)
  double max_mag_uT = 10000.0;  ///< |mag| above this is rejected
};

/// Per-kind counts of rejected or unusual input.
struct FilterCounters {
  uint64_t gyr_ok = 0, acc_ok = 0, mag_ok = 0;
  uint64_t nonfinite = 0;     ///< NaN or Inf component
  uint64_t zero_vector = 0;   ///< acc or mag of (near) zero norm
  uint64_t out_of_range = 0;  ///< absurd magnitude
  uint64_t bad_time = 0;      ///< timestamp not after the previous one of the same stream
  uint64_t gaps = 0;          ///< gaps longer than 5 nominal periods
};

/// Coefficients derived from params and the sampling periods (not saved; recomputed).
struct FilterCoeffs {
  double gyr_ts_s = 0, acc_ts_s = 0, mag_ts_s = 0;
  filt::LowpassCoeffs acc_lp, rest_gyr_lp, rest_acc_lp, mag_norm_dip_lp;
  filt::HardIronCoeffs hard_iron;
  double k_hard_iron_select = 0;
  int hard_iron_decim = 1;  ///< estimator runs every hard_iron_decim magnetometer samples
  double k_mag = 0, k_mag_ref = 0;
  double k_latency = 0, k_latency_hp = 0;
  int bias_decim = 1;           ///< bias KF runs every bias_decim acc samples (about 100 Hz)
  double bias_ts_s = 0;         ///< its period
  filt::LowpassCoeffs bias_lp;  ///< tau_acc low-pass at the bias KF rate
  double bias_p0 = 0, bias_v = 0, bias_motion_w = 0, bias_vertical_w = 0, bias_rest_w = 0;
  double heading_q_rad2_s = 0, heading_r0_rad2 = 0;
  int gain_reg_decim = 1;  ///< its regressor is low-passed every gain_reg_decim bias steps
  filt::LowpassCoeffs gain_reg_lp;
  int gain_decim = 1;  ///< gyro-gain KF runs every gain_decim bias steps (about 10 Hz)
  double gain_p0 = 0, gain_v = 0, gain_w = 0;
};

/// Everything that evolves; can be saved and restored (plain data).
struct FilterState {
  Eigen::Quaterniond q_gyr = Eigen::Quaterniond::Identity();    ///< sensor -> almost-inertial
  Eigen::Quaterniond q_acc = Eigen::Quaterniond::Identity();    ///< almost-inertial -> 6D earth
  double delta_rad = 0;                                         ///< heading offset 6D earth -> ENU
  Eigen::Quaterniond q_delta = Eigen::Quaterniond::Identity();  ///< rotation by delta_rad
  double delta_var_rad2 = 10;  ///< heading variance (Kalman heading)
  bool have_gyr = false, have_acc = false, have_mag = false;
  int64_t t_gyr_ns = 0, t_acc_ns = 0, t_mag_ns = 0;
  double gyr_ts_nom_s = 0, acc_ts_nom_s = 0, mag_ts_nom_s = 0;  ///< tracked sampling periods
  int gyr_long_run = 0, acc_long_run = 0, mag_long_run = 0;     ///< see stream_dt
  Eigen::Vector3d last_gyr_rad_s = Eigen::Vector3d::Zero();
  filt::LatencyEstimator mag_latency;
  // inclination
  filt::Lowpass<3> acc_lp;
  Eigen::Vector3d last_acc_earth = Eigen::Vector3d::UnitZ();
  // bias
  Eigen::Vector3d bias_rad_s = Eigen::Vector3d::Zero();
  Eigen::Matrix3d bias_p = Eigen::Matrix3d::Zero();  ///< in (0.01 deg/s)^2
  bool bias_p_init = false;
  int bias_n = 0;                                           ///< acc samples in this block
  Eigen::Vector2d bias_corr_sum = Eigen::Vector2d::Zero();  ///< horizontal corrections summed
  filt::Lowpass<9> motion_r_lp;
  filt::Lowpass<2> motion_bias_lp;
  // gyro gain G (row-major 3x3, gyro reads (I + G) w + b) and its Kalman filter
  Eigen::Matrix<double, 9, 1> gain = Eigen::Matrix<double, 9, 1>::Zero();
  Eigen::Matrix<double, 9, 9> gain_p = Eigen::Matrix<double, 9, 9>::Zero();  ///< in gain^2
  bool gain_p_init = false;
  int gain_n = 0;                                           ///< bias steps since the last
  Eigen::Vector3d gyr_sum_rad_s = Eigen::Vector3d::Zero();  ///< gyro summed over a bias block
  filt::Lowpass<18> gain_reg_lp;  ///< low-pass of the regressor R_ri w_j, rows 0 and 1 of R
  Eigen::Matrix<double, 2, 9> gain_reg = Eigen::Matrix<double, 2, 9>::Zero();      ///< its output
  Eigen::Matrix<double, 2, 9> gain_reg_sum = Eigen::Matrix<double, 2, 9>::Zero();  ///< block sum
  int gain_reg_n = 0;
  // rest
  bool rest = false;
  double rest_t_s = 0;
  double rest_dev_gyr2 = 0, rest_dev_acc2 = 0;
  filt::Lowpass<3> rest_gyr_lp, rest_acc_lp;
  Eigen::Vector3d rest_last_gyr_lp = Eigen::Vector3d::Zero();
  // magnetometer
  bool mag_disturbed = true;
  bool mag_have_ref = false;     ///< a reference field was accepted (start-up is over)
  bool mag_heading_set = false;  ///< the first field sample set the provisional heading
  double k_mag_init = 1.0;
  double mag_ref_norm = 0, mag_ref_dip = 0;
  double mag_undisturbed_t_s = 0, mag_reject_t_s = 0;
  double mag_cand_norm = -1, mag_cand_dip = 0, mag_cand_t_s = 0;
  double mag_cand_age_s = 0;  ///< time the field has stayed consistent with the candidate
  filt::Lowpass<2> mag_norm_dip_lp;
  double mag_norm_dip[2] = {0, 0};
  // hard-iron offset
  filt::HardIronEstimator hard_iron;
  int hi_n = 0;                ///< magnetometer samples since the last estimator step
  double hi_dt_s = 0;          ///< and their time
  double hi_select = 0;        ///< low-passed score difference without / with the offset
  double hi_weight = 0;        ///< weight of the offset applied (0..1)
  double hi_consistent_s = 0;  ///< time the estimator's innovations have stayed consistent
  int hi_restarts_seen = 0;    ///< its restart count then
  Eigen::Vector3d hi_applied_uT = Eigen::Vector3d::Zero();  ///< offset subtracted
  bool hi_applied_consistent = false;                       ///< ... by the consistency path
};

/// Everything a consumer reads after an update, in one plain struct (AttitudeFilter::output()).
struct FilterOutput {
  Eigen::Quaterniond q_earth_sensor = Eigen::Quaterniond::Identity();     ///< 9D (or 6D)
  Eigen::Quaterniond q_earth_sensor_6d = Eigen::Quaterniond::Identity();  ///< gyro + acc
  Eigen::Vector3d gyro_bias_rad_s = Eigen::Vector3d::Zero();
  double heading_sigma_rad = 0;
  bool at_rest = false;
  /// The field is currently rejected by the disturbance tests (a reference exists and the
  /// field does not match it); the heading runs on the gyro.
  bool mag_disturbed = false;
  /// No reference field accepted yet (start-up): the heading follows the field
  /// provisionally (while it is self-consistent) and must not be trusted yet; distinct from
  /// mag_disturbed (never both).
  bool mag_no_reference = false;
  Eigen::Vector3d hard_iron_uT = Eigen::Vector3d::Zero();  ///< offset subtracted (sensor frame)
  double hard_iron_sigma_uT = 0;  ///< its largest one-sigma (directions above the gate unused)
};

/// Quaternion attitude filter for one sensor. Allocation-free update.
class AttitudeFilter {
 public:
  explicit AttitudeFilter(const FilterParams& p = {});

  /// Feeds one sample; gyr/acc/mag are used according to s.valid and may arrive in separate
  /// samples at different rates. Periods come from s.t_host_ns per stream.
  void update(const ImuSample& s);

  /// 9D orientation (sensor -> ENU) once a magnetometer sample was accepted, else 6D.
  Eigen::Quaterniond q_earth_sensor() const;
  /// 6D orientation (sensor -> a z-up frame with arbitrary but slowly drifting heading).
  Eigen::Quaterniond q_earth_sensor_6d() const;
  bool at_rest() const { return st_.rest; }
  /// Field currently rejected: a reference field exists and this one fails its tests (the
  /// heading runs on the gyro). False during start-up, see mag_no_reference().
  bool mag_disturbed() const {
    return st_.have_mag && st_.mag_have_ref && p_.mag_dist_rejection && st_.mag_disturbed;
  }
  /// Magnetometer samples arrive but no reference field was accepted yet (start-up): the
  /// 9D heading is provisional. False without a magnetometer or without disturbance tests.
  bool mag_no_reference() const {
    return st_.have_mag && p_.mag_dist_rejection && !st_.mag_have_ref;
  }
  FilterOutput output() const;
  /// The magnetometer's heading correction so far: q_earth_sensor() = Rz(this) *
  /// q_earth_sensor_6d() (rad, wrapped to +-pi). NaN while there is none (no magnetometer
  /// sample yet) or it has not converged (heading one-sigma above kSettledHeadingSigmaDeg:
  /// the first second of start-up).
  double mag_heading_rad() const;
  static constexpr double kSettledHeadingSigmaDeg = 5.0;
  /// A reference field (norm, dip in the 6D frame) has been accepted or imposed.
  bool mag_has_reference() const { return st_.have_mag && st_.mag_have_ref; }
  double mag_reference_norm_uT() const { return st_.mag_ref_norm; }
  double mag_reference_dip_rad() const { return st_.mag_ref_dip; }
  /// The current (smoothed) field's norm, uT, and dip, rad, in the 6D frame.
  double mag_field_norm_uT() const { return st_.mag_norm_dip[0]; }
  double mag_field_dip_rad() const { return st_.mag_norm_dip[1]; }
  /// Hard-iron offset currently subtracted from the magnetometer, uT (sensor frame).
  Eigen::Vector3d hard_iron_uT() const { return st_.hi_applied_uT; }
  /// Largest one-sigma of the hard-iron estimate over all directions, uT.
  double hard_iron_sigma_uT() const { return st_.hard_iron.offset_sigma_uT(); }
  Eigen::Vector3d gyro_bias_rad_s() const { return st_.bias_rad_s; }
  /// Estimated gyro gain error G (scale on the diagonal, misalignment off it): the gyro reads
  /// (I + G) w + bias; the filter integrates the rate corrected by it.
  Eigen::Matrix3d gyro_gain() const;
  /// One-sigma heading uncertainty of the 9D output, rad (large before any magnetometer).
  double heading_sigma_rad() const;

  FilterState state() const { return st_; }
  void set_state(const FilterState& s);
  const FilterCounters& counters() const { return cnt_; }
  const FilterParams& params() const { return p_; }
  void reset();

 private:
  void update_gyr(const Eigen::Vector3d& gyr, double dt_s);
  void update_acc(const Eigen::Vector3d& acc, double dt_s);
  void update_mag(const Eigen::Vector3d& mag, double dt_s);
  void end_mag_startup();
  void select_hard_iron(const Eigen::Vector3d& m_raw_e, const Eigen::Vector3d& m_corr_e);
  /// Squared deviation of a field (norm, dip) from a reference, in units of the disturbance
  /// thresholds (mag_norm_th, mag_dip_th_deg).
  double field_deviation2(double norm, double dip, double ref_norm, double ref_dip) const;
  void update_bias(const Eigen::Vector3d& acc_earth_unfiltered_corr, double dt_s);
  void update_gain(const Eigen::Vector2d& residual, const Eigen::Matrix<double, 2, 9>& reg,
                   const Eigen::Matrix3d& r_lp);
  /// long_run: consecutive intervals over 5 nominal periods (three re-set the period).
  bool stream_dt(int64_t t_ns, bool& have, int64_t& t_last, double& ts_nom, int& long_run,
                 double& dt_s);
  void refresh_coeffs();

  FilterParams p_;
  FilterCoeffs c_;
  FilterState st_;
  FilterCounters cnt_;
};

}  // namespace mocap
