// AttitudeFilter: strapdown + almost-inertial acc low-pass + scalar heading, with bias Kalman
// filter, rest detection and magnetic-disturbance handling. Equations in docs/filter.md.
#include "mocap/filter/attitude_filter.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include <numbers>
#include "mocap/core/units.hpp"
#include "mocap/filter/input_check.hpp"

namespace mocap {
namespace {

double wrap_pi(double a) {
  if (a > std::numbers::pi) a -= 2 * std::numbers::pi;
  if (a < -std::numbers::pi) a += 2 * std::numbers::pi;
  if (!(std::abs(a) <= std::numbers::pi)) a = std::remainder(a, 2 * std::numbers::pi);
  return a;
}

/// Dip of an earth-frame field of norm n (rad, positive when the field points down).
double dip_rad(const Eigen::Vector3d& m_e, double n) {
  return -std::asin(std::clamp(m_e.z() / n, -1.0, 1.0));
}

Eigen::Quaterniond heading_quat(double delta_rad) {
  return Eigen::Quaterniond(std::cos(delta_rad / 2), 0, 0, std::sin(delta_rad / 2));
}

}  // namespace

AttitudeFilter::AttitudeFilter(const FilterParams& p) : p_(p) {
  reset();
}

void AttitudeFilter::reset() {
  st_ = FilterState{};
  cnt_ = FilterCounters{};
  c_ = FilterCoeffs{};
  refresh_coeffs();
}

void AttitudeFilter::set_state(const FilterState& s) {
  st_ = s;
  refresh_coeffs();
}

void AttitudeFilter::refresh_coeffs() {
  auto sq = [](double x) { return x * x; };
  // Sampling periods: tracked per stream; before a stream's second sample borrow another's.
  const double fallback = st_.gyr_ts_nom_s > 0   ? st_.gyr_ts_nom_s
                          : st_.acc_ts_nom_s > 0 ? st_.acc_ts_nom_s
                                                 : 0.01;
  c_.gyr_ts_s = st_.gyr_ts_nom_s > 0 ? st_.gyr_ts_nom_s : fallback;
  c_.acc_ts_s = st_.acc_ts_nom_s > 0 ? st_.acc_ts_nom_s : c_.gyr_ts_s;
  c_.mag_ts_s = st_.mag_ts_nom_s > 0 ? st_.mag_ts_nom_s : c_.acc_ts_s;

  c_.acc_lp = filt::butterworth(p_.tau_acc_s, c_.acc_ts_s);
  c_.rest_gyr_lp = filt::butterworth(p_.rest_filter_tau_s, c_.gyr_ts_s);
  c_.rest_acc_lp = filt::butterworth(p_.rest_filter_tau_s, c_.acc_ts_s);
  c_.mag_norm_dip_lp = filt::butterworth(p_.mag_current_tau_s, c_.mag_ts_s);
  c_.k_mag = filt::gain_from_tau(p_.tau_mag_s, c_.mag_ts_s);
  // Kalman heading: q = sigma^2 / tau, r = sigma^2 tau / T gives the time constant tau_mag
  // and the steady-state one-sigma heading_sigma_deg in an undisturbed field, at any rate.
  const double sh2 = sq(p_.heading_sigma_deg * kRadPerDeg);
  c_.heading_q_rad2_s = sh2 / std::max(p_.tau_mag_s, 1e-9);
  c_.heading_r0_rad2 = sh2 * p_.tau_mag_s / c_.mag_ts_s;
  c_.k_mag_ref = filt::gain_from_tau(p_.mag_ref_tau_s, c_.mag_ts_s);
  // Hard-iron estimator: fixed period in seconds; variances relative to the field norm.
  c_.hard_iron_decim =
      std::max(1, static_cast<int>(std::lround(p_.hard_iron_step_s / c_.mag_ts_s)));
  c_.hard_iron.p0_offset_rel2 = sq(p_.hard_iron_sigma0);
  c_.hard_iron.q_offset_rel2_s = c_.hard_iron.p0_offset_rel2 / std::max(p_.hard_iron_tau_s, 1e-9);
  c_.hard_iron.q_field_rel2_s = sq(p_.hard_iron_field_rw_deg * kRadPerDeg);
  c_.hard_iron.r_rel2 = sq(p_.hard_iron_noise);
  c_.hard_iron.gate_rel2 = sq(p_.hard_iron_gate);
  c_.hard_iron.min_offset_rel = p_.hard_iron_min_offset;
  c_.hard_iron.min_sigmas = p_.hard_iron_min_sigmas;
  c_.hard_iron.min_sigmas_consistent = p_.hard_iron_consistent_min_sigmas;
  c_.hard_iron.k_nis =
      filt::gain_from_tau(p_.hard_iron_nis_tau_s, c_.hard_iron_decim * c_.mag_ts_s);
  c_.hard_iron.nis_max = p_.hard_iron_nis_max;
  c_.k_hard_iron_select =
      filt::gain_from_tau(p_.hard_iron_select_tau_s, c_.hard_iron_decim * c_.mag_ts_s);
  c_.k_latency = filt::gain_from_tau(p_.mag_latency_tau_s, c_.mag_ts_s);
  c_.k_latency_hp = filt::gain_from_tau(p_.mag_latency_hp_tau_s, c_.mag_ts_s);

  // The bias KF runs decimated to about 100 Hz: bias changes over minutes.
  c_.bias_decim = std::max(1, static_cast<int>(std::lround(0.01 / c_.acc_ts_s)));
  c_.bias_ts_s = c_.bias_decim * c_.acc_ts_s;
  c_.bias_lp = filt::butterworth(p_.tau_acc_s, c_.bias_ts_s);
  // Bias KF in units of (0.01 deg/s)^2: uncertainty grows by 0.1 deg/s per forgetting time.
  c_.bias_p0 = sq(p_.bias_sigma_init_deg_s * 100.0);
  c_.bias_v = sq(0.1 * 100.0) * c_.bias_ts_s / p_.bias_forgetting_time_s;
  const double p_motion = sq(p_.bias_sigma_motion_deg_s * 100.0);
  c_.bias_motion_w = sq(p_motion) / c_.bias_v + p_motion;
  c_.bias_vertical_w = c_.bias_motion_w / std::max(p_.bias_vertical_forgetting, 1e-10);
  const double p_rest = sq(p_.bias_sigma_rest_deg_s * 100.0);
  c_.bias_rest_w = sq(p_rest) / c_.bias_v + p_rest;
  // Gyro-gain KF: every gain_decim bias steps (about 10 Hz; the residual is low-passed with
  // tau_acc, so sub-sampling it loses little), in gain units; the measurement noise is the
  // motion bias update's per step, in (rad/s)^2.
  c_.gain_decim = std::max(1, static_cast<int>(std::lround(0.1 / c_.bias_ts_s)));
  c_.gain_reg_decim = std::max(1, static_cast<int>(std::lround(0.04 / c_.bias_ts_s)));
  c_.gain_reg_lp = filt::butterworth(p_.tau_acc_s, c_.gain_reg_decim * c_.bias_ts_s);
  const double gain_ts = c_.gain_decim * c_.bias_ts_s;
  c_.gain_p0 = sq(p_.gyr_gain_sigma_init);
  c_.gain_v = sq(1e-3) * gain_ts / std::max(p_.gyr_gain_forgetting_time_s, 1e-9);
  c_.gain_w = c_.bias_motion_w * sq(0.01 * kRadPerDeg);
}

// Period of one stream from its timestamps. Returns false (and counts) for a timestamp that
// does not advance. dt_s is 0 for a stream's first sample.
bool AttitudeFilter::stream_dt(int64_t t_ns, bool& have, int64_t& t_last, double& ts_nom,
                               int& long_run, double& dt_s) {
  if (!have) {
    have = true;
    t_last = t_ns;
    dt_s = 0;
    return true;
  }
  if (t_ns <= t_last) {
    ++cnt_.bad_time;
    return false;
  }
  dt_s = static_cast<double>(t_ns - t_last) * 1e-9;
  t_last = t_ns;
  if (ts_nom <= 0) {
    ts_nom = dt_s;
    refresh_coeffs();
    return true;
  }
  // Track the nominal period: small jitter by averaging; a genuinely different rate by
  // steady drift; gaps (> 5 periods) are counted and leave the period alone, unless they come
  // three in a row: then the period in use is wrong (a first interval from samples read in
  // one burst, stamped microseconds apart) or the rate really dropped, and the interval is
  // the period. Without that a period locked on 56 us held every time constant 180x too
  // long (the demo's sensors never got a reference field).
  if (dt_s <= 5 * ts_nom) long_run = 0;
  if (dt_s < 2 * ts_nom && dt_s > 0.5 * ts_nom) {
    ts_nom += 0.02 * (dt_s - ts_nom);
  } else if (dt_s <= 0.5 * ts_nom) {
    ts_nom *= 0.95;
  } else if (dt_s <= 5 * ts_nom) {
    ts_nom *= 1.02;
  } else {
    ++cnt_.gaps;
    if (++long_run >= 3) {
      ts_nom = dt_s;
      long_run = 0;
    }
  }
  // Re-derive coefficients when a tracked period moved more than 2 % from the one in use.
  auto moved = [](double nom, double used) {
    return nom > 0 && std::abs(nom - used) > 0.02 * used;
  };
  if (moved(st_.gyr_ts_nom_s, c_.gyr_ts_s) || moved(st_.acc_ts_nom_s, c_.acc_ts_s) ||
      moved(st_.mag_ts_nom_s, c_.mag_ts_s))
    refresh_coeffs();
  return true;
}

void AttitudeFilter::update(const ImuSample& s) {
  double dt_s = 0;
  if (s.has(kFieldGyr)) {
    if (filt::check_vector(s.gyr_rad_s, 0.0, p_.max_gyr_rad_s, cnt_) &&
        stream_dt(s.t_host_ns, st_.have_gyr, st_.t_gyr_ns, st_.gyr_ts_nom_s, st_.gyr_long_run,
                  dt_s)) {
      ++cnt_.gyr_ok;
      update_gyr(s.gyr_rad_s, dt_s);
    }
  }
  if (s.has(kFieldAcc)) {
    if (filt::check_vector(s.acc_m_s2, 1e-3, p_.max_acc_m_s2, cnt_) &&
        stream_dt(s.t_host_ns, st_.have_acc, st_.t_acc_ns, st_.acc_ts_nom_s, st_.acc_long_run,
                  dt_s)) {
      ++cnt_.acc_ok;
      update_acc(s.acc_m_s2, dt_s);
    }
  }
  if (s.has(kFieldMag)) {
    if (filt::check_vector(s.mag_uT, 1e-6, p_.max_mag_uT, cnt_) &&
        stream_dt(s.t_host_ns, st_.have_mag, st_.t_mag_ns, st_.mag_ts_nom_s, st_.mag_long_run,
                  dt_s)) {
      ++cnt_.mag_ok;
      update_mag(s.mag_uT, dt_s);
    }
  }
}

void AttitudeFilter::update_gyr(const Eigen::Vector3d& gyr, double dt_s) {
  // Rest detection, gyro part: deviation from the low-passed rate.
  const double ts = c_.gyr_ts_s;
  const auto& lp = st_.rest_gyr_lp.step(gyr.data(), c_.rest_gyr_lp, p_.rest_filter_tau_s, ts);
  st_.rest_last_gyr_lp = Eigen::Vector3d(lp[0], lp[1], lp[2]);
  st_.rest_dev_gyr2 = (gyr - st_.rest_last_gyr_lp).squaredNorm();
  const double clip = p_.bias_clip_deg_s * kRadPerDeg;
  if (st_.rest_dev_gyr2 >=
          (p_.rest_th_gyr_deg_s * kRadPerDeg) * (p_.rest_th_gyr_deg_s * kRadPerDeg) ||
      st_.rest_last_gyr_lp.cwiseAbs().maxCoeff() > clip) {
    st_.rest_t_s = 0;
    st_.rest = false;
  }
  st_.last_gyr_rad_s = gyr;
  if (dt_s <= 0) return;  // first sample: nothing to integrate yet
  const double t = std::min(dt_s, p_.max_gap_s);
  // Exact quaternion exponential of the bias- and gain-corrected rate held over the period.
  Eigen::Vector3d w = gyr - st_.bias_rad_s;
  if (p_.gyr_gain_sigma_init > 0) {
    w -= gyro_gain() * w;
  }
  const double n = w.norm();
  const double angle = n * t;
  if (angle > 1e-12) {
    const double c = std::cos(angle / 2), sn = std::sin(angle / 2) / n;
    const Eigen::Quaterniond dq(c, sn * w.x(), sn * w.y(), sn * w.z());
    st_.q_gyr = st_.q_gyr * dq;
    st_.q_gyr.normalize();
  }
}

void AttitudeFilter::update_acc(const Eigen::Vector3d& acc, double dt_s) {
  (void)dt_s;
  const double ts = c_.acc_ts_s;
  // Rest detection, acc part.
  const auto& alp = st_.rest_acc_lp.step(acc.data(), c_.rest_acc_lp, p_.rest_filter_tau_s, ts);
  st_.rest_dev_acc2 = (acc - Eigen::Vector3d(alp[0], alp[1], alp[2])).squaredNorm();
  const double thg = p_.rest_th_gyr_deg_s * kRadPerDeg, tha = p_.rest_th_acc_m_s2;
  if (st_.rest_dev_gyr2 >= thg * thg || st_.rest_dev_acc2 >= tha * tha ||
      st_.rest_last_gyr_lp.cwiseAbs().maxCoeff() > p_.bias_clip_deg_s * kRadPerDeg) {
    st_.rest_t_s = 0;
    st_.rest = false;
  } else {
    st_.rest_t_s += ts;
    if (st_.rest_t_s >= p_.rest_min_t_s) st_.rest = true;
  }

  // Low-pass in the almost-inertial frame, then into the 6D earth frame.
  // Acc into the almost-inertial frame.
  const Eigen::Vector3d acc_i = st_.q_gyr * acc;
  const auto& f = st_.acc_lp.step(acc_i.data(), c_.acc_lp, p_.tau_acc_s, ts);
  const Eigen::Vector3d acc_f(f[0], f[1], f[2]);
  Eigen::Vector3d acc_e = st_.q_acc * acc_f;
  const double an = acc_e.norm();
  if (!(an > 1e-9)) return;
  acc_e /= an;
  st_.last_acc_earth = acc_e;
  // Shortest rotation taking acc_e onto +z, applied fully.
  const double qw = std::sqrt(std::max((acc_e.z() + 1.0) / 2.0, 0.0));
  Eigen::Quaterniond qc;
  if (qw > 1e-6)
    qc = Eigen::Quaterniond(qw, 0.5 * acc_e.y() / qw, -0.5 * acc_e.x() / qw, 0);
  else
    qc = Eigen::Quaterniond(0, 1, 0, 0);
  st_.q_acc = qc * st_.q_acc;
  st_.q_acc.normalize();

  st_.bias_corr_sum += acc_e.head<2>();
  st_.gyr_sum_rad_s += st_.last_gyr_rad_s;
  if (++st_.bias_n >= c_.bias_decim) {
    update_bias(Eigen::Vector3d(st_.bias_corr_sum.x(), st_.bias_corr_sum.y(), 1.0), c_.bias_ts_s);
    st_.bias_n = 0;
    st_.bias_corr_sum.setZero();
    st_.gyr_sum_rad_s.setZero();
  }
}

// acc_e holds the horizontal inclination corrections summed over the last ts seconds.
void AttitudeFilter::update_bias(const Eigen::Vector3d& acc_e, double ts) {
  if (!st_.bias_p_init) {
    st_.bias_p = Eigen::Matrix3d::Identity() * c_.bias_p0;
    st_.bias_p_init = true;
  }
  const Eigen::Matrix3d r6 = (st_.q_acc * st_.q_gyr).toRotationMatrix();
  Eigen::Matrix3d r_lp = Eigen::Matrix3d::Identity();
  Eigen::Vector2d rb_lp = Eigen::Vector2d::Zero();
  const bool gain_on = p_.gyr_gain_sigma_init > 0 && p_.motion_bias_est;
  // The error the current estimates remove: bias plus gain times the block's mean rate.
  Eigen::Vector3d b_applied = st_.bias_rad_s;
  if (gain_on) {
    const Eigen::Vector3d w = st_.gyr_sum_rad_s / c_.bias_decim - st_.bias_rad_s;
    b_applied += gyro_gain() * w;
    // Regressor of G (row-major entries ij) in the horizontal rows r: R_ri w_j, summed and
    // low-passed every gain_reg_decim steps (about 25 Hz; tau_acc is seconds).
    for (int r = 0; r < 2; ++r)
      for (int i = 0; i < 3; ++i)
        st_.gain_reg_sum.block<1, 3>(r, 3 * i) += r6(r, i) * w.transpose();
    if (++st_.gain_reg_n >= c_.gain_reg_decim) {
      double g[18];
      const double inv = 1.0 / st_.gain_reg_n;
      for (int r = 0; r < 2; ++r)
        for (int k = 0; k < 9; ++k)
          g[9 * r + k] = st_.gain_reg_sum(r, k) * inv;
      const auto& gl =
          st_.gain_reg_lp.step(g, c_.gain_reg_lp, p_.tau_acc_s, ts * c_.gain_reg_decim);
      for (int r = 0; r < 2; ++r)
        for (int k = 0; k < 9; ++k)
          st_.gain_reg(r, k) = gl[9 * r + k];
      st_.gain_reg_sum.setZero();
      st_.gain_reg_n = 0;
    }
  }
  const Eigen::Matrix<double, 2, 9>& reg = st_.gain_reg;
  if (p_.motion_bias_est) {
    // Row-major copy so the 9 channels are the rows of R.
    double rr[9];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        rr[3 * i + j] = r6(i, j);
    const auto& rl = st_.motion_r_lp.step(rr, c_.bias_lp, p_.tau_acc_s, ts);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        r_lp(i, j) = rl[3 * i + j];
    const double rb[2] = {r6.row(0).dot(b_applied), r6.row(1).dot(b_applied)};
    const auto& bl = st_.motion_bias_lp.step(rb, c_.bias_lp, p_.tau_acc_s, ts);
    rb_lp = Eigen::Vector2d(bl[0], bl[1]);
  }

  Eigen::Vector3d e, w;
  Eigen::Matrix3d cm;
  const Eigen::Vector3d& b = st_.bias_rad_s;
  if (st_.rest && p_.rest_bias_est) {
    e = st_.rest_last_gyr_lp - b;
    cm = Eigen::Matrix3d::Identity();
    w.setConstant(c_.bias_rest_w);
  } else if (p_.motion_bias_est) {
    e.x() = -acc_e.y() / ts + rb_lp.x() - r_lp.row(0).dot(b);
    e.y() = acc_e.x() / ts + rb_lp.y() - r_lp.row(1).dot(b);
    e.z() = -r_lp.row(2).dot(b);
    if (gain_on) {
      e.head<2>() -= reg * st_.gain;
      if (++st_.gain_n >= c_.gain_decim) {
        st_.gain_n = 0;
        const double clip = p_.bias_clip_deg_s * kRadPerDeg;
        update_gain(e.head<2>().cwiseMax(-clip).cwiseMin(clip), reg, r_lp);
      }
    }
    cm = r_lp;
    w = Eigen::Vector3d(c_.bias_motion_w, c_.bias_motion_w, c_.bias_vertical_w);
  } else {
    w.setConstant(-1);
  }
  // Process noise while the uncertainty is below its initial value.
  for (int i = 0; i < 3; ++i)
    if (st_.bias_p(i, i) < c_.bias_p0) st_.bias_p(i, i) += c_.bias_v;
  if (w.x() < 0) return;
  const double clip = p_.bias_clip_deg_s * kRadPerDeg;
  e = e.cwiseMax(-clip).cwiseMin(clip);
  const Eigen::Matrix3d s = cm * st_.bias_p * cm.transpose() + Eigen::Matrix3d(w.asDiagonal());
  const Eigen::Matrix3d k = st_.bias_p * cm.transpose() * s.inverse();
  st_.bias_rad_s = (st_.bias_rad_s + k * e).cwiseMax(-clip).cwiseMin(clip);
  st_.bias_p -= k * cm * st_.bias_p;
}

// Gyro-gain Kalman update: residual = reg * (G - G_est) + bias error + noise (rad/s).
void AttitudeFilter::update_gain(const Eigen::Vector2d& residual,
                                 const Eigen::Matrix<double, 2, 9>& reg,
                                 const Eigen::Matrix3d& r_lp) {
  if (!st_.gain_p_init) {
    st_.gain_p = Eigen::Matrix<double, 9, 9>::Identity() * c_.gain_p0;
    st_.gain_p_init = true;
  }
  for (int i = 0; i < 9; ++i)
    if (st_.gain_p(i, i) < c_.gain_p0) st_.gain_p(i, i) += c_.gain_v;
  // Measurement noise: the motion update's plus the current bias uncertainty.
  const Eigen::Matrix<double, 2, 3> cb = r_lp.topRows<2>() * (0.01 * kRadPerDeg);
  Eigen::Matrix2d s = cb * st_.bias_p * cb.transpose();
  s.diagonal().array() += c_.gain_w;
  const Eigen::Matrix<double, 9, 2> ph = st_.gain_p * reg.transpose();
  s += reg * ph;
  const Eigen::Matrix<double, 9, 2> k = ph * s.inverse();
  const double clip = p_.gyr_gain_clip;
  st_.gain = (st_.gain + k * residual).cwiseMax(-clip).cwiseMin(clip);
  st_.gain_p -= k * ph.transpose();
}

Eigen::Matrix3d AttitudeFilter::gyro_gain() const {
  return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(st_.gain.data());
}

double AttitudeFilter::field_deviation2(double norm, double dip, double ref_norm,
                                        double ref_dip) const {
  const double dn = (norm - ref_norm) / (p_.mag_norm_th * ref_norm);
  const double dd = (dip - ref_dip) / (p_.mag_dip_th_deg * kRadPerDeg);
  return dn * dn + dd * dd;
}

// Applies the gated offset only while it explains a disturbance: the squared norm/dip
// deviations from the reference (relative to the thresholds) without and with it; or, with a
// lower significance, while the estimator's innovations have stayed consistent.
void AttitudeFilter::select_hard_iron(const Eigen::Vector3d& m_raw_e,
                                      const Eigen::Vector3d& m_corr_e) {
  const filt::HardIronEstimator& h = st_.hard_iron;
  bool consistent = false;
  if (p_.hard_iron_consistent_nis > 0) {
    if (h.restarts != st_.hi_restarts_seen || !(h.nis < p_.hard_iron_consistent_nis))
      st_.hi_consistent_s = 0;
    else
      st_.hi_consistent_s += c_.hard_iron_decim * c_.mag_ts_s;
    st_.hi_restarts_seen = h.restarts;
    consistent = st_.mag_ref_norm > 0 && st_.hi_consistent_s >= p_.hard_iron_consistent_s;
  }
  if (p_.hard_iron_select_margin <= 0) {
    st_.hi_weight = 1;
  } else if (st_.mag_ref_norm <= 0 || h.used_uT.isZero()) {
    // Nothing to compare with before a reference field exists (a field that varies around
    // a magnet at start-up must not be "explained" by an offset), or nothing to apply.
    st_.hi_select = 0;
    st_.hi_weight = 0;
  } else {
    auto score = [&](const Eigen::Vector3d& m) {
      const double n = m.norm();
      if (!(n > 0)) return 0.0;
      return std::min(field_deviation2(n, dip_rad(m, n), st_.mag_ref_norm, st_.mag_ref_dip), 25.0);
    };
    st_.hi_select += c_.k_hard_iron_select * (score(m_raw_e) - score(m_corr_e) - st_.hi_select);
    st_.hi_weight = std::clamp(st_.hi_select / p_.hard_iron_select_margin, 0.0, 1.0);
  }
  st_.hi_applied_uT = st_.hi_weight * h.used_uT;
  st_.hi_applied_consistent = false;
  if (consistent && h.used_consistent_uT.norm() > st_.hi_applied_uT.norm()) {
    st_.hi_applied_uT = h.used_consistent_uT;
    st_.hi_applied_consistent = true;
  }
}

void AttitudeFilter::update_mag(const Eigen::Vector3d& mag_raw, double dt_s) {
  const double ts = c_.mag_ts_s;
  const Eigen::Quaterniond q6 = st_.q_acc * st_.q_gyr;
  if (p_.hard_iron_tau_s > 0) {
    // Hard-iron estimator (decimated), fed with the latency-compensated raw field.
    st_.hi_dt_s += dt_s > 0 ? dt_s : ts;
    if (++st_.hi_n >= c_.hard_iron_decim) {
      const double lat_s =
          p_.mag_latency_tau_s > 0
              ? st_.mag_latency.latency_s(p_.mag_latency_min_rate_deg_s * kRadPerDeg,
                                          p_.mag_latency_max_s)
              : 0.0;
      const Eigen::Vector3d w = st_.last_gyr_rad_s - st_.bias_rad_s;
      const Eigen::Vector3d m_c = mag_raw - lat_s * w.cross(mag_raw - st_.hard_iron.used_uT);
      const Eigen::Matrix3d r6 = q6.toRotationMatrix();
      st_.hard_iron.step(m_c, r6, std::min(st_.hi_dt_s, 1.0), st_.mag_ref_norm, c_.hard_iron);
      st_.hi_n = 0;
      st_.hi_dt_s = 0;
      select_hard_iron(r6 * m_c, r6 * (m_c - st_.hard_iron.used_uT));
    }
  }
  const Eigen::Vector3d mag = mag_raw - hard_iron_uT();
  // Into the 6D earth frame, compensated for the latency behind the gyro: a field read L
  // late is the current one rotated by w L, so v = q6 (w x m) is its rate of change there.
  Eigen::Vector3d m_e = q6 * mag;
  if (p_.mag_latency_tau_s > 0) {
    const Eigen::Vector3d v_e = q6 * (st_.last_gyr_rad_s - st_.bias_rad_s).cross(mag);
    st_.mag_latency.step(m_e, v_e, c_.k_latency_hp, c_.k_latency);
    m_e -= st_.mag_latency.latency_s(p_.mag_latency_min_rate_deg_s * kRadPerDeg,
                                     p_.mag_latency_max_s) *
           v_e;
  }

  if (p_.mag_dist_rejection) {
    const double n = m_e.norm();
    const double nd[2] = {n, dip_rad(m_e, n)};
    const auto& f = st_.mag_norm_dip_lp.step(nd, c_.mag_norm_dip_lp, p_.mag_current_tau_s, ts);
    st_.mag_norm_dip[0] = f[0];
    st_.mag_norm_dip[1] = f[1];
    const double norm = f[0], dip = f[1];
    const double dip_th = p_.mag_dip_th_deg * kRadPerDeg;
    if (std::abs(norm - st_.mag_ref_norm) < p_.mag_norm_th * st_.mag_ref_norm &&
        std::abs(dip - st_.mag_ref_dip) < dip_th) {
      st_.mag_undisturbed_t_s += ts;
      if (st_.mag_undisturbed_t_s >= p_.mag_min_undisturbed_time_s) {
        st_.mag_disturbed = false;
        st_.mag_ref_norm += c_.k_mag_ref * (norm - st_.mag_ref_norm);
        st_.mag_ref_dip += c_.k_mag_ref * (dip - st_.mag_ref_dip);
      }
    } else {
      st_.mag_undisturbed_t_s = 0;
      st_.mag_disturbed = true;
    }
    // Candidate for a new reference field: self-consistent while rotating.
    if (std::abs(norm - st_.mag_cand_norm) < p_.mag_norm_th * st_.mag_cand_norm &&
        std::abs(dip - st_.mag_cand_dip) < dip_th) {
      // A new field replacing a known one must be seen while rotating (a static local
      // disturbance stays self-consistent at rest); the very first field needs no rotation.
      if (st_.mag_ref_norm == 0 ||
          st_.rest_last_gyr_lp.norm() >= p_.mag_new_min_gyr_deg_s * kRadPerDeg)
        st_.mag_cand_t_s += ts;
      st_.mag_cand_age_s += ts;
      st_.mag_cand_norm += c_.k_mag_ref * (norm - st_.mag_cand_norm);
      st_.mag_cand_dip += c_.k_mag_ref * (dip - st_.mag_cand_dip);
      if (st_.mag_disturbed &&
          (st_.mag_cand_t_s >= p_.mag_new_time_s ||
           (st_.mag_ref_norm == 0 && st_.mag_cand_t_s >= p_.mag_new_first_time_s))) {
        if (!st_.mag_have_ref) end_mag_startup();
        st_.mag_ref_norm = st_.mag_cand_norm;
        st_.mag_ref_dip = st_.mag_cand_dip;
        st_.mag_disturbed = false;
        st_.mag_undisturbed_t_s = p_.mag_min_undisturbed_time_s;
      }
    } else {
      st_.mag_cand_t_s = 0;
      st_.mag_cand_age_s = 0;
      st_.mag_cand_norm = norm;
      st_.mag_cand_dip = dip;
    }
  }

  // Heading measurement.
  const double err = wrap_pi(std::atan2(m_e.x(), m_e.y()) - st_.delta_rad);
  // Kalman heading. Predict: the heading drifts by the nominal process noise plus what the
  // gyro-bias uncertainty allows. Measurement variance: nominal (steady state = tau_mag),
  // inflated by the squared disturbance indicators, each relative to its threshold.
  const double sb2 = st_.bias_p(2, 2) * (0.01 * kRadPerDeg) * (0.01 * kRadPerDeg);
  st_.delta_var_rad2 += (c_.heading_q_rad2_s + sb2) * (dt_s > 0 ? dt_s : ts);  // real gap
  double r = c_.heading_r0_rad2;
  if (p_.mag_dist_rejection && (st_.mag_ref_norm > 0 || st_.mag_cand_norm > 0)) {
    // Deviations from the reference, or before one exists from the candidate.
    const bool ref = st_.mag_ref_norm > 0;
    const double rn = ref ? st_.mag_ref_norm : st_.mag_cand_norm;
    const double rd = ref ? st_.mag_ref_dip : st_.mag_cand_dip;
    double score =
        p_.mag_trust_weight * field_deviation2(st_.mag_norm_dip[0], st_.mag_norm_dip[1], rn, rd);
    // A field that was rejected recently is trusted less until the rejection budget is repaid.
    score += st_.mag_reject_t_s / p_.tau_mag_s;
    r *= 1.0 + score;
  }
  double k = st_.delta_var_rad2 / (st_.delta_var_rad2 + r);
  bool use_init = true;  // the start-up schedule counts only samples that pass the tests
  if (p_.mag_dist_rejection) {
    if (!st_.mag_have_ref) {
      // Provisional heading: follows the field only while it stays consistent with the
      // candidate reference (a field whose norm or dip changes is no earth field); the very
      // first sample sets it, so there is a heading from the start.
      use_init = false;
      if (!st_.mag_heading_set)
        k = 1;
      else if (st_.mag_cand_age_s < p_.mag_min_undisturbed_time_s)
        k = 0;
      st_.mag_heading_set = true;
    } else if (st_.mag_disturbed) {
      use_init = false;
      if (st_.mag_reject_t_s <= p_.mag_max_rejection_time_s) {
        st_.mag_reject_t_s += ts;
        k = 0;
      } else {
        k = std::min(k, c_.k_mag) / p_.mag_rejection_factor;  // backstop: nominal gain at most
      }
    } else {
      st_.mag_reject_t_s = std::max(st_.mag_reject_t_s - p_.mag_rejection_factor * ts, 0.0);
    }
  }
  if (st_.k_mag_init != 0 && use_init) {
    k = std::max(k, st_.k_mag_init);
    st_.k_mag_init = st_.k_mag_init / (st_.k_mag_init + 1);
    if (st_.k_mag_init * p_.tau_mag_s < ts) st_.k_mag_init = 0;
  }
  st_.delta_rad = wrap_pi(st_.delta_rad + k * err);
  // Joseph form: valid for the gains the rejection and start-up rules impose as well.
  st_.delta_var_rad2 = (1 - k) * (1 - k) * st_.delta_var_rad2 + k * k * r;
  st_.q_delta = heading_quat(st_.delta_rad);
}

FilterOutput AttitudeFilter::output() const {
  FilterOutput o;
  o.q_earth_sensor = q_earth_sensor();
  o.q_earth_sensor_6d = q_earth_sensor_6d();
  o.gyro_bias_rad_s = st_.bias_rad_s;
  o.heading_sigma_rad = heading_sigma_rad();
  o.at_rest = st_.rest;
  o.mag_disturbed = mag_disturbed();
  o.mag_no_reference = mag_no_reference();
  o.hard_iron_uT = hard_iron_uT();
  o.hard_iron_sigma_uT = hard_iron_sigma_uT();
  return o;
}

Eigen::Quaterniond AttitudeFilter::q_earth_sensor_6d() const {
  return st_.q_acc * st_.q_gyr;
}

Eigen::Quaterniond AttitudeFilter::q_earth_sensor() const {
  if (!st_.have_mag) return st_.q_acc * st_.q_gyr;
  return st_.q_delta * (st_.q_acc * st_.q_gyr);
}

// End of start-up (a first reference field accepted or imposed): converge afresh on samples
// that pass the tests from now on. The schedule restarts at the gain the heading variance
// implies (1 after a full reset, about the Kalman gain when the provisional heading is kept).
void AttitudeFilter::end_mag_startup() {
  st_.mag_have_ref = true;
  st_.k_mag_init = st_.delta_var_rad2 / (st_.delta_var_rad2 + c_.heading_r0_rad2);
}

double AttitudeFilter::heading_sigma_rad() const {
  if (!st_.have_mag) return std::numbers::pi;
  // Predicted to the newest gyro sample (the magnetometer may be slower or missing).
  const double since_mag_s = std::max(static_cast<double>(st_.t_gyr_ns - st_.t_mag_ns), 0.0) * 1e-9;
  const double sb2 = st_.bias_p(2, 2) * (0.01 * kRadPerDeg) * (0.01 * kRadPerDeg);
  return std::sqrt(std::max(st_.delta_var_rad2 + (c_.heading_q_rad2_s + sb2) * since_mag_s, 0.0));
}

double AttitudeFilter::mag_heading_rad() const {
  if (!st_.have_mag || !(heading_sigma_rad() <= kSettledHeadingSigmaDeg * kRadPerDeg))
    return std::numeric_limits<double>::quiet_NaN();
  return st_.delta_rad;
}

}  // namespace mocap
