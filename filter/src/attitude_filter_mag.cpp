// AttitudeFilter's magnetometer stages, one function each (update_mag calls them in order):
// hard-iron estimate and selection, the field into the 6D frame with latency compensation,
// disturbance tests and reference field, Kalman heading with rejection and start-up rules.
// Equations in docs/filter.md.
#include "mocap/filter/attitude_filter.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "mocap/core/units.hpp"
#include "mocap/filter/filter_constants.hpp"
#include "mocap/filter/small_angle.hpp"

namespace mocap {
namespace {

double wrap_pi(double a) {
  if (a > std::numbers::pi) a -= 2 * std::numbers::pi;
  if (a < -std::numbers::pi) a += 2 * std::numbers::pi;
  if (!(std::abs(a) <= std::numbers::pi)) a = std::remainder(a, 2 * std::numbers::pi);
  return a;
}

/// Dip of an earth-frame field of norm n (rad, positive when the field points down), expected
/// near near_rad: atan2(-z, horizontal norm) by the series around the grid angle nearest to it
/// (no asin: a field sample's dip is within a few degrees of the smoothed one nearly always).
double dip_rad(const Eigen::Vector3d& m_e, double n, double near_rad) {
  double dip;
  if (atan2_near(-m_e.z(), std::sqrt(m_e.x() * m_e.x() + m_e.y() * m_e.y()), near_rad, dip))
    return dip;
  return -std::asin(std::clamp(m_e.z() / n, -1.0, 1.0));
}

Eigen::Quaterniond heading_quat(double delta_rad) {
  return Eigen::Quaterniond(std::cos(delta_rad / 2), 0, 0, std::sin(delta_rad / 2));
}

}  // namespace

double AttitudeFilter::field_deviation2(double norm, double dip, double ref_norm,
                                        double ref_dip) const {
  const double dn = (norm - ref_norm) / (p_.mag_dist.norm_th * ref_norm);
  const double dd = (dip - ref_dip) * c_.mag_dist.inv_dip_th_rad;
  return dn * dn + dd * dd;
}

double AttitudeFilter::mag_latency_s() const {
  return p_.mag_latency.tau_s > 0
             ? st_.mag_latency.latency_s(kMagLatencyMinRate_deg_s * kRadPerDeg, kMagLatencyMax_s)
             : 0.0;
}

// A field sample: hard iron, into the 6D frame (latency-compensated), disturbance tests,
// heading.
[[gnu::flatten]] void AttitudeFilter::update_mag(const Eigen::Vector3d& mag_raw, double dt_s) {
  const Eigen::Quaterniond q6 = st_.inclination.q_acc * st_.strapdown.q_gyr;
  if (p_.hard_iron.tau_s > 0) {
    // The estimator runs every hard_iron.decim field samples (out of line, like every rare
    // step): in between only its clock advances.
    HardIronState& h = st_.hard_iron;
    h.dt_s += dt_s > 0 ? dt_s : c_.ts.mag_s;
    if (++h.n >= c_.hard_iron.decim) update_hard_iron(mag_raw, q6);
  }
  const Eigen::Vector3d mag = mag_raw - st_.hard_iron.applied_uT;
  const Eigen::Vector3d m_e = mag_to_earth(mag, q6);
  if (st_.upset.checking) upset_mag(mag);  // nothing to do while nothing was clipped
  // The heading the field implies against the gyro-propagated one (the 6D frame turns with the
  // gyro, so in a homogeneous field this stays near 0).
  const double err = heading_innovation(m_e);
  if (p_.mag_dist.rejection) update_mag_disturbance(m_e, err);
  update_heading(m_e, err, dt_s);
}

// The field's heading atan2(m_x, m_y) in the 6D frame minus the estimate delta_rad, wrapped. It is
// the angle of the horizontal field turned back by the estimate (cos and sin of delta from
// q_delta): small nearly always, then its arctangent's series, without atan2.
double AttitudeFilter::heading_innovation(const Eigen::Vector3d& m_e) const {
  const Eigen::Quaterniond& q = st_.heading.q_delta;
  const double cd = q.w() * q.w() - q.z() * q.z(), sd = 2 * q.w() * q.z();
  const double along = m_e.y() * cd + m_e.x() * sd, across = m_e.x() * cd - m_e.y() * sd;
  if (along > 0 && std::abs(across) <= kAtanQuarterMax * along) return atan_quarter(across / along);
  return wrap_pi(std::atan2(m_e.x(), m_e.y()) - st_.heading.delta_rad);
}

// Hard-iron estimator (decimated to hard_iron.step_s), fed with the latency-compensated raw
// field; then the choice of the offset subtracted.
void AttitudeFilter::update_hard_iron(const Eigen::Vector3d& mag_raw,
                                      const Eigen::Quaterniond& q6) {
  HardIronState& h = st_.hard_iron;
  const double lat_s = mag_latency_s();
  const Eigen::Vector3d w = st_.strapdown.last_gyr_rad_s - st_.bias.rad_s;
  const Eigen::Vector3d m_c = mag_raw - lat_s * w.cross(mag_raw - h.est.used_uT);
  const Eigen::Matrix3d r6 = q6.toRotationMatrix();
  h.est.step(m_c, r6, std::min(h.dt_s, 1.0), st_.mag_dist.ref_norm, c_.hard_iron.est);
  h.n = 0;
  h.dt_s = 0;
  select_hard_iron(r6 * m_c, r6 * (m_c - h.est.used_uT));
}

// Applies the gated offset only while it explains a disturbance: the squared norm/dip
// deviations from the reference (relative to the thresholds) without and with it.
void AttitudeFilter::select_hard_iron(const Eigen::Vector3d& m_raw_e,
                                      const Eigen::Vector3d& m_corr_e) {
  HardIronState& hs = st_.hard_iron;
  const HardIronEstimator& h = hs.est;
  const double ref_norm = st_.mag_dist.ref_norm;
  if (ref_norm <= 0 || h.used_uT.isZero()) {
    // Nothing to compare with before a reference field exists (a field that varies around
    // a magnet at start-up must not be "explained" by an offset), or nothing to apply.
    hs.select = 0;
    hs.weight = 0;
  } else {
    auto score = [&](const Eigen::Vector3d& m) {
      const double n = m.norm();
      if (!(n > 0)) return 0.0;
      return std::min(
          field_deviation2(n, dip_rad(m, n, st_.mag_dist.ref_dip), ref_norm, st_.mag_dist.ref_dip),
          25.0);
    };
    hs.select += c_.hard_iron.k_select * (score(m_raw_e) - score(m_corr_e) - hs.select);
    hs.weight = std::clamp(hs.select / kHardIronSelectMargin, 0.0, 1.0);
  }
  hs.applied_uT = hs.weight * h.used_uT;
}

// Into the 6D earth frame, compensated for the latency behind the gyro: a field read L late
// is the current one rotated by w L, so v = q6 (w x m) is its rate of change there.
Eigen::Vector3d AttitudeFilter::mag_to_earth(const Eigen::Vector3d& mag,
                                             const Eigen::Quaterniond& q6) {
  Eigen::Vector3d m_e = q6 * mag;
  if (p_.mag_latency.tau_s > 0) {
    const Eigen::Vector3d v_e = q6 * (st_.strapdown.last_gyr_rad_s - st_.bias.rad_s).cross(mag);
    st_.mag_latency.step(m_e, v_e, c_.mag_latency.k_hp, c_.mag_latency.k);
    m_e -= mag_latency_s() * v_e;
  }
  return m_e;
}

// Disturbance tests: the smoothed norm and dip of the field in the 6D frame and its heading
// against the gyro-propagated one, each against a reference tracked slowly while undisturbed;
// and a candidate for a new reference (self-consistent while rotating).
void AttitudeFilter::update_mag_disturbance(const Eigen::Vector3d& m_e, double err_rad) {
  MagDisturbanceState& d = st_.mag_dist;
  const MagDisturbanceParams& p = p_.mag_dist;
  const double ts = c_.ts.mag_s;
  const double n = m_e.norm();
  const double nd[2] = {n, dip_rad(m_e, n, d.norm_dip[1])};
  const auto& f = d.norm_dip_lp.step(nd, c_.mag_dist.norm_dip_lp, kMagCurrentTau_s, ts);
  d.norm_dip[0] = f[0];
  d.norm_dip[1] = f[1];
  const double norm = f[0], dip = f[1];
  const double dip_th = p.dip_th_deg * kRadPerDeg;
  // The heading innovation: the field's heading in the 6D frame minus the estimate. While the
  // field is rejected the estimate turns only with the gyro, so a field that turns against it
  // (a magnet or steel near the sensor, which may leave norm and dip alone) shows here; while
  // it is followed the innovation's slow part is the estimate's lag, tracked as its reference.
  // A deviation beyond the threshold plus three sigma of the heading is a disturbance (once
  // the heading has settled: before, the field is what sets it).
  d.head_dev_rad += c_.mag_dist.k_head * (err_rad - d.head_dev_rad);
  const double head = d.head_dev_rad;
  // Settled: a reference, the start-up gain schedule over, no clipped gyro sample being
  // checked (the heading may have been lost: upset recovery). From then on the heading is
  // taken to be as uncertain as the field disagrees with it, so it converges on the field
  // instead of locking out.
  const bool settled = d.have_ref && st_.heading.k_init == 0 && !st_.upset.checking;
  if (settled && !d.head_settled) {
    st_.heading.delta_var_rad2 = std::max(st_.heading.delta_var_rad2, head * head);
    d.ref_head_rad = 0;
  }
  d.head_settled = settled;
  if (!settled) d.ref_head_rad = head;
  const double dref = head - d.ref_head_rad;
  const bool head_ok = dref * dref < c_.mag_dist.head_th2_rad2 + 9 * st_.heading.delta_var_rad2;
  if (std::abs(norm - d.ref_norm) < p.norm_th * d.ref_norm && std::abs(dip - d.ref_dip) < dip_th &&
      head_ok) {
    d.undisturbed_t_s += ts;
    if (d.undisturbed_t_s >= kMagMinUndisturbedTime_s) {
      d.disturbed = false;
      d.ref_norm += c_.mag_dist.k_ref * (norm - d.ref_norm);
      d.ref_dip += c_.mag_dist.k_ref * (dip - d.ref_dip);
      d.ref_head_rad += c_.mag_dist.k_ref * dref;
    }
  } else {
    d.undisturbed_t_s = 0;
    d.disturbed = true;
  }
  const double dh = head - d.cand_head_rad;
  if (std::abs(norm - d.cand_norm) < p.norm_th * d.cand_norm &&
      std::abs(dip - d.cand_dip) < dip_th && dh * dh < 4 * c_.mag_dist.head_th2_rad2) {
    // (The candidate is one field while its heading stays within twice the threshold: wider
    // than the test, as the field's heading wanders more than its norm and dip in motion.)
    // A new field replacing a known one must be seen while rotating (a static local
    // disturbance stays self-consistent at rest); the very first field needs no rotation.
    const double min_gyr_rad_s = kMagNewMinGyr_deg_s * kRadPerDeg;
    if (d.ref_norm == 0 || st_.rest.last_gyr_lp.squaredNorm() >= min_gyr_rad_s * min_gyr_rad_s)
      d.cand_t_s += ts;
    d.cand_age_s += ts;
    d.cand_norm += c_.mag_dist.k_ref * (norm - d.cand_norm);
    d.cand_dip += c_.mag_dist.k_ref * (dip - d.cand_dip);
    d.cand_head_rad += c_.mag_dist.k_ref * dh;
    if (d.disturbed &&
        (d.cand_t_s >= p.new_time_s || (d.ref_norm == 0 && d.cand_t_s >= kMagNewFirstTime_s))) {
      if (!d.have_ref) end_mag_startup();
      d.ref_norm = d.cand_norm;
      d.ref_dip = d.cand_dip;
      d.disturbed = false;
      d.undisturbed_t_s = kMagMinUndisturbedTime_s;
      if (settled) {
        // The new field's heading disagrees with the gyro-propagated one by the candidate's
        // innovation: the heading is that uncertain, and converges on the new field.
        HeadingState& h = st_.heading;
        h.delta_var_rad2 = std::max(h.delta_var_rad2, d.cand_head_rad * d.cand_head_rad);
        d.ref_head_rad = 0;
      }
    }
  } else {
    d.cand_t_s = 0;
    d.cand_age_s = 0;
    d.cand_norm = norm;
    d.cand_dip = dip;
    d.cand_head_rad = head;
  }
}

// Kalman heading. Predict: the heading drifts by the nominal process noise plus what the
// gyro-bias uncertainty allows. Update with the field's heading in the 6D frame, at the gain
// the rejection and start-up rules leave; Joseph form (valid for those gains as well).
void AttitudeFilter::update_heading(const Eigen::Vector3d& m_e, double err, double dt_s) {
  HeadingState& h = st_.heading;
  h.last_m_e = m_e;
  const double sb2 = st_.bias.p(2, 2) * (0.01 * kRadPerDeg) * (0.01 * kRadPerDeg);
  h.delta_var_rad2 += (c_.heading.q_rad2_s + sb2) * (dt_s > 0 ? dt_s : c_.ts.mag_s);  // real gap
  const double r = heading_measurement_var();
  const double k = heading_gain(h.delta_var_rad2 / (h.delta_var_rad2 + r));
  const double step_rad = k * err;
  h.delta_rad = wrap_pi(h.delta_rad + step_rad);
  h.delta_var_rad2 = (1 - k) * (1 - k) * h.delta_var_rad2 + k * k * r;
  // q_delta turned by the step: a small one (nearly every sample) by the series, without
  // sincos; w >= 0 as for delta_rad in [-pi, pi].
  const double half2 = 0.25 * step_rad * step_rad;
  if (half2 == 0) return;
  if (half2 <= kSmallAngle2) {
    const double c = cos_small(half2), s = 0.5 * step_rad * sinc_small(half2);
    Eigen::Quaterniond& q = h.q_delta;
    q = Eigen::Quaterniond(q.w() * c - q.z() * s, 0, 0, q.w() * s + q.z() * c);
    if (q.w() < 0) q.coeffs() = -q.coeffs();
    renormalize(q);
  } else {
    h.q_delta = heading_quat(h.delta_rad);
  }
}

// Nominal (steady state = tau_mag), inflated by the squared disturbance indicators, each
// relative to its threshold, and by the rejection time not yet repaid.
double AttitudeFilter::heading_measurement_var() const {
  const MagDisturbanceState& d = st_.mag_dist;
  double r = c_.heading.r0_rad2;
  if (p_.mag_dist.rejection && (d.ref_norm > 0 || d.cand_norm > 0)) {
    // Deviations from the reference, or before one exists from the candidate.
    const bool ref = d.ref_norm > 0;
    const double rn = ref ? d.ref_norm : d.cand_norm;
    const double rd = ref ? d.ref_dip : d.cand_dip;
    double score =
        p_.mag_dist.trust_weight * field_deviation2(d.norm_dip[0], d.norm_dip[1], rn, rd);
    if (ref) {  // the heading's deviation, once a reference exists
      const double x = d.head_dev_rad - d.ref_head_rad;
      score += p_.mag_dist.trust_weight * x * x * c_.mag_dist.inv_head_th2_rad2;
    }
    score += d.reject_t_s * c_.heading.inv_tau_mag_s;
    r *= 1.0 + score;
  }
  return r;
}

// Rejection: K = 0 while disturbed for up to max_rejection_time_s, then at most the nominal
// gain / rejection_factor. Start-up: the provisional heading follows the field only while it
// stays consistent with the candidate reference (a field whose norm or dip changes is no earth
// field; the very first sample sets it); K >= k_init (1/N over tau_mag_s), counting only
// samples that pass the tests.
double AttitudeFilter::heading_gain(double k) {
  const double ts = c_.ts.mag_s;
  MagDisturbanceState& d = st_.mag_dist;
  HeadingState& h = st_.heading;
  bool use_init = true;
  if (p_.mag_dist.rejection) {
    if (!d.have_ref) {
      use_init = false;
      if (!h.set)
        k = 1;
      else if (d.cand_age_s < kMagMinUndisturbedTime_s)
        k = 0;
      h.set = true;
    } else if (d.disturbed) {
      use_init = false;
      if (d.reject_t_s <= kMagMaxRejectionTime_s) {
        d.reject_t_s += ts;
        k = 0;
      } else {
        k = std::min(k, c_.heading.k_mag) / kMagRejectionFactor;  // backstop: nominal gain at most
      }
    } else {
      d.reject_t_s = std::max(d.reject_t_s - kMagRejectionFactor * ts, 0.0);
    }
  }
  if (h.k_init != 0 && use_init) {
    k = std::max(k, h.k_init);
    h.k_init = h.k_init / (h.k_init + 1);
    if (h.k_init * p_.heading.tau_mag_s < ts) h.k_init = 0;
  }
  return k;
}

// End of start-up (a first reference field accepted): converge afresh on samples that pass the
// tests from now on. The schedule restarts at the gain the heading variance implies (1 after a
// full reset, about the Kalman gain when the provisional heading is kept).
void AttitudeFilter::end_mag_startup() {
  st_.mag_dist.have_ref = true;
  st_.heading.k_init =
      st_.heading.delta_var_rad2 / (st_.heading.delta_var_rad2 + c_.heading.r0_rad2);
}

// Predicted to the newest gyro sample (the magnetometer may be slower or missing).
double AttitudeFilter::heading_sigma_rad() const {
  if (!st_.mag_timing.have) return std::numbers::pi;
  const double since_mag_s =
      std::max(static_cast<double>(st_.gyr_timing.t_ns - st_.mag_timing.t_ns), 0.0) * 1e-9;
  const double sb2 = st_.bias.p(2, 2) * (0.01 * kRadPerDeg) * (0.01 * kRadPerDeg);
  return std::sqrt(
      std::max(st_.heading.delta_var_rad2 + (c_.heading.q_rad2_s + sb2) * since_mag_s, 0.0));
}

}  // namespace mocap
