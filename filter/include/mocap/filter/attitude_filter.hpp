// The per-sensor attitude filter: gyro strapdown + inclination from low-passed acc in an
// almost-inertial frame + magnetometer heading as a separate scalar, with online gyro-bias
// estimation, rest detection and magnetic-disturbance rejection (VQF structure, extended).
// Parameters (FilterParams) and state (FilterState) are per-stage structs in their own headers;
// FilterOutput is what consumers read. See docs/filter.md for the equations, parameters and
// measured accuracy.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <limits>

#include "mocap/core/imu_sample.hpp"
#include "mocap/filter/filter_coeffs.hpp"
#include "mocap/filter/filter_params.hpp"
#include "mocap/filter/filter_state.hpp"

namespace mocap {

/// Per-kind counts of rejected or unusual input.
struct FilterCounters {
  uint64_t gyr_ok = 0, acc_ok = 0, mag_ok = 0;
  uint64_t nonfinite = 0;         ///< NaN or Inf component
  uint64_t zero_vector = 0;       ///< acc or mag of (near) zero norm
  uint64_t out_of_range = 0;      ///< absurd magnitude
  uint64_t bad_time = 0;          ///< timestamp not after the previous one of the same stream
  uint64_t gaps = 0;              ///< gaps longer than 5 nominal periods
  uint64_t upset_recoveries = 0;  ///< orientation set anew after clipped gyro samples
};

/// The filter's state flags, as a consumer reads them.
struct FilterFlags {
  bool at_rest = false;  ///< gyro and acc deviations below the rest thresholds long enough
  /// The field is currently rejected by the disturbance tests (a reference exists and the
  /// field does not match it); the heading runs on the gyro.
  bool mag_disturbed = false;
  /// Magnetometer samples arrive but no reference field was accepted yet (start-up): the
  /// heading follows the field provisionally (while it is self-consistent) and must not be
  /// trusted yet; distinct from mag_disturbed (never both). False without a magnetometer or
  /// without disturbance tests.
  bool mag_no_reference = false;
  bool mag_reference = false;  ///< a reference field (norm, dip in the 6D frame) was accepted
};

/// Everything a consumer reads after an update, in one plain struct (AttitudeFilter::output()).
struct FilterOutput {
  /// Sensor -> ENU: 9D once a magnetometer sample was accepted, else the 6D orientation.
  Eigen::Quaterniond q_earth_sensor = Eigen::Quaterniond::Identity();
  /// Sensor -> a z-up frame with arbitrary but slowly drifting heading (gyro + acc).
  Eigen::Quaterniond q_earth_sensor_6d = Eigen::Quaterniond::Identity();
  Eigen::Vector3d gyro_bias_rad_s = Eigen::Vector3d::Zero();  ///< estimated gyro bias
  /// rad, one-sigma heading uncertainty of the 9D output (pi before any magnetometer sample),
  /// predicted to the newest gyro sample.
  double heading_sigma_rad = 0;
  /// rad, the magnetometer's heading correction so far: q_earth_sensor = Rz(this) *
  /// q_earth_sensor_6d (wrapped to +-pi). NaN while there is none (no magnetometer sample yet)
  /// or it has not converged (heading_sigma_rad above kSettledHeadingSigmaDeg: the first
  /// second of start-up).
  double mag_heading_rad = std::numeric_limits<double>::quiet_NaN();
  static constexpr double kSettledHeadingSigmaDeg = 5.0;
  FilterFlags flags;
  Eigen::Vector3d hard_iron_uT = Eigen::Vector3d::Zero();  ///< offset subtracted (sensor frame)
  double hard_iron_sigma_uT = 0;  ///< its largest one-sigma (directions above the gate unused)
  /// The newest field (hard iron removed) in the 6D frame, uT; zero before any. Its heading
  /// there is what the heading follows (a body tracker watches it for a local field,
  /// rig/local_field_watch.hpp).
  Eigen::Vector3d mag_6d_uT = Eigen::Vector3d::Zero();
};

/// Quaternion attitude filter for one sensor. Allocation-free update.
class AttitudeFilter {
 public:
  explicit AttitudeFilter(const FilterParams& p = {});

  /// Feeds one sample; gyr/acc/mag are used according to s.valid and may arrive in separate
  /// samples at different rates. Periods come from s.t_host_ns per stream.
  void update(const ImuSample& s);
  /// What a consumer reads: orientation, bias, heading uncertainty, flags, hard iron.
  FilterOutput output() const;

  FilterState state() const { return st_; }  ///< save (plain data)
  void set_state(const FilterState& s);      ///< restore
  const FilterCounters& counters() const { return cnt_; }
  const FilterParams& params() const { return p_; }
  void reset();

 private:
  // One function per stage (docs/filter.md, "Algorithm"); each reads p_ and c_, writes st_.
  void update_gyr(const Eigen::Vector3d& gyr, double dt_s);
  void update_acc(const Eigen::Vector3d& acc, double dt_s);
  void update_mag(const Eigen::Vector3d& mag, double dt_s);
  void update_rest_gyr(const Eigen::Vector3d& gyr);
  void update_rest_acc(const Eigen::Vector3d& acc);
  bool update_inclination(const Eigen::Vector3d& acc);
  // Upset recovery (attitude_filter_upset.cpp).
  /// A gyro sample at full scale: the strapdown may have lost rotation; the check begins.
  [[gnu::noinline]] void note_clipped_gyr();
  /// The field (hard iron removed) into the check's fast low-pass.
  [[gnu::noinline]] void upset_mag(const Eigen::Vector3d& mag);
  /// The check, with each acc sample: a fresh orientation from fast-low-passed acc (and field)
  /// against the filter's; a steady disagreement is corrected.
  [[gnu::noinline]] void check_upset(const Eigen::Vector3d& acc);
  [[gnu::noinline]] void recover_upset(const Eigen::Quaterniond& q_acc, double delta_rad,
                                       bool with_heading);
  void update_bias(const Eigen::Vector3d& acc_earth_unfiltered_corr, double dt_s);
  void update_gain_regressor(const Eigen::Matrix3d& r6, const Eigen::Vector3d& w, double ts);
  [[gnu::noinline]] void update_gain(const Eigen::Vector2d& residual,
                                     const Eigen::Matrix<double, 2, 9>& reg,
                                     const Eigen::Matrix3d& r_lp);
  [[gnu::noinline]] void update_hard_iron(const Eigen::Vector3d& mag_raw,
                                          const Eigen::Quaterniond& q6);
  void select_hard_iron(const Eigen::Vector3d& m_raw_e, const Eigen::Vector3d& m_corr_e);
  /// The (hard-iron corrected) field in the 6D earth frame, compensated for the magnetometer's
  /// latency behind the gyro (and the latency estimate updated).
  Eigen::Vector3d mag_to_earth(const Eigen::Vector3d& mag, const Eigen::Quaterniond& q6);
  /// The field's heading in the 6D frame minus the heading estimate (wrapped to +-pi).
  double heading_innovation(const Eigen::Vector3d& m_e) const;
  /// err_rad: the field's heading in the 6D frame minus the heading estimate.
  void update_mag_disturbance(const Eigen::Vector3d& m_e, double err_rad);
  void update_heading(const Eigen::Vector3d& m_e, double err_rad, double dt_s);
  /// The heading measurement's variance: nominal, inflated by the soft trust score.
  double heading_measurement_var() const;
  /// The heading gain after the rejection and start-up rules (k: the Kalman gain).
  double heading_gain(double k);
  [[gnu::noinline]] void end_mag_startup();
  /// Squared deviation of a field (norm, dip) from a reference, in units of the disturbance
  /// thresholds (mag_dist.norm_th, mag_dist.dip_th_deg).
  double field_deviation2(double norm, double dip, double ref_norm, double ref_dip) const;
  /// Latency of the magnetometer behind the gyro, s (0 when the estimate is off).
  double mag_latency_s() const;
  double heading_sigma_rad() const;
  bool stream_dt(int64_t t_ns, StreamTiming& timing, double& dt_s);
  [[gnu::noinline]] void refresh_coeffs();

  FilterParams p_;
  FilterCoeffs c_;
  FilterState st_;
  FilterCounters cnt_;
};

}  // namespace mocap
