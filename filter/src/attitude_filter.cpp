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
  const double fallback = st_.gyr_timing.ts_nom_s > 0   ? st_.gyr_timing.ts_nom_s
                          : st_.acc_timing.ts_nom_s > 0 ? st_.acc_timing.ts_nom_s
                                                        : 0.01;
  c_.gyr_ts_s = st_.gyr_timing.ts_nom_s > 0 ? st_.gyr_timing.ts_nom_s : fallback;
  c_.acc_ts_s = st_.acc_timing.ts_nom_s > 0 ? st_.acc_timing.ts_nom_s : c_.gyr_ts_s;
  c_.mag_ts_s = st_.mag_timing.ts_nom_s > 0 ? st_.mag_timing.ts_nom_s : c_.acc_ts_s;

  c_.acc_lp = butterworth(p_.inclination.tau_acc_s, c_.acc_ts_s);
  c_.rest_gyr_lp = butterworth(p_.rest.filter_tau_s, c_.gyr_ts_s);
  c_.rest_acc_lp = butterworth(p_.rest.filter_tau_s, c_.acc_ts_s);
  c_.mag_norm_dip_lp = butterworth(p_.mag_dist.current_tau_s, c_.mag_ts_s);
  c_.k_mag = gain_from_tau(p_.heading.tau_mag_s, c_.mag_ts_s);
  // Kalman heading: q = sigma^2 / tau, r = sigma^2 tau / T gives the time constant tau_mag
  // and the steady-state one-sigma heading_sigma_deg in an undisturbed field, at any rate.
  const double sh2 = sq(p_.heading.sigma_deg * kRadPerDeg);
  c_.heading_q_rad2_s = sh2 / std::max(p_.heading.tau_mag_s, 1e-9);
  c_.heading_r0_rad2 = sh2 * p_.heading.tau_mag_s / c_.mag_ts_s;
  c_.k_mag_ref = gain_from_tau(p_.mag_dist.ref_tau_s, c_.mag_ts_s);
  // Hard-iron estimator: fixed period in seconds; variances relative to the field norm.
  c_.hard_iron_decim =
      std::max(1, static_cast<int>(std::lround(p_.hard_iron.step_s / c_.mag_ts_s)));
  c_.hard_iron.p0_offset_rel2 = sq(p_.hard_iron.sigma0);
  c_.hard_iron.q_offset_rel2_s = c_.hard_iron.p0_offset_rel2 / std::max(p_.hard_iron.tau_s, 1e-9);
  c_.hard_iron.q_field_rel2_s = sq(p_.hard_iron.field_rw_deg * kRadPerDeg);
  c_.hard_iron.r_rel2 = sq(p_.hard_iron.noise);
  c_.hard_iron.gate_rel2 = sq(p_.hard_iron.gate);
  c_.hard_iron.min_offset_rel = p_.hard_iron.min_offset;
  c_.hard_iron.min_sigmas = p_.hard_iron.min_sigmas;
  c_.hard_iron.min_sigmas_consistent = p_.hard_iron.consistent_min_sigmas;
  c_.hard_iron.k_nis = gain_from_tau(p_.hard_iron.nis_tau_s, c_.hard_iron_decim * c_.mag_ts_s);
  c_.hard_iron.nis_max = p_.hard_iron.nis_max;
  c_.k_hard_iron_select =
      gain_from_tau(p_.hard_iron.select_tau_s, c_.hard_iron_decim * c_.mag_ts_s);
  c_.k_latency = gain_from_tau(p_.mag_latency.tau_s, c_.mag_ts_s);
  c_.k_latency_hp = gain_from_tau(p_.mag_latency.hp_tau_s, c_.mag_ts_s);

  // The bias KF runs decimated to about 100 Hz: bias changes over minutes.
  c_.bias_decim = std::max(1, static_cast<int>(std::lround(0.01 / c_.acc_ts_s)));
  c_.bias_ts_s = c_.bias_decim * c_.acc_ts_s;
  c_.bias_lp = butterworth(p_.inclination.tau_acc_s, c_.bias_ts_s);
  // Bias KF in units of (0.01 deg/s)^2: uncertainty grows by 0.1 deg/s per forgetting time.
  c_.bias_p0 = sq(p_.bias.sigma_init_deg_s * 100.0);
  c_.bias_v = sq(0.1 * 100.0) * c_.bias_ts_s / p_.bias.forgetting_time_s;
  const double p_motion = sq(p_.bias.sigma_motion_deg_s * 100.0);
  c_.bias_motion_w = sq(p_motion) / c_.bias_v + p_motion;
  c_.bias_vertical_w = c_.bias_motion_w / std::max(p_.bias.vertical_forgetting, 1e-10);
  const double p_rest = sq(p_.bias.sigma_rest_deg_s * 100.0);
  c_.bias_rest_w = sq(p_rest) / c_.bias_v + p_rest;
  // Gyro-gain KF: every gain_decim bias steps (about 10 Hz; the residual is low-passed with
  // tau_acc, so sub-sampling it loses little), in gain units; the measurement noise is the
  // motion bias update's per step, in (rad/s)^2.
  c_.gain_decim = std::max(1, static_cast<int>(std::lround(0.1 / c_.bias_ts_s)));
  c_.gain_reg_decim = std::max(1, static_cast<int>(std::lround(0.04 / c_.bias_ts_s)));
  c_.gain_reg_lp = butterworth(p_.inclination.tau_acc_s, c_.gain_reg_decim * c_.bias_ts_s);
  const double gain_ts = c_.gain_decim * c_.bias_ts_s;
  c_.gain_p0 = sq(p_.gyr_gain.sigma_init);
  c_.gain_v = sq(1e-3) * gain_ts / std::max(p_.gyr_gain.forgetting_time_s, 1e-9);
  c_.gain_w = c_.bias_motion_w * sq(0.01 * kRadPerDeg);
}

// Period of one stream from its timestamps. Returns false (and counts) for a timestamp that
// does not advance. dt_s is 0 for a stream's first sample.
bool AttitudeFilter::stream_dt(int64_t t_ns, StreamTiming& timing, double& dt_s) {
  if (!timing.have) {
    timing.have = true;
    timing.t_ns = t_ns;
    dt_s = 0;
    return true;
  }
  if (t_ns <= timing.t_ns) {
    ++cnt_.bad_time;
    return false;
  }
  dt_s = static_cast<double>(t_ns - timing.t_ns) * 1e-9;
  timing.t_ns = t_ns;
  double& ts_nom = timing.ts_nom_s;
  int& long_run = timing.long_run;
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
  if (moved(st_.gyr_timing.ts_nom_s, c_.gyr_ts_s) || moved(st_.acc_timing.ts_nom_s, c_.acc_ts_s) ||
      moved(st_.mag_timing.ts_nom_s, c_.mag_ts_s))
    refresh_coeffs();
  return true;
}

void AttitudeFilter::update(const ImuSample& s) {
  double dt_s = 0;
  if (s.has(kFieldGyr)) {
    if (check_vector(s.gyr_rad_s, 0.0, p_.input.max_gyr_rad_s, cnt_) &&
        stream_dt(s.t_host_ns, st_.gyr_timing, dt_s)) {
      ++cnt_.gyr_ok;
      update_gyr(s.gyr_rad_s, dt_s);
    }
  }
  if (s.has(kFieldAcc)) {
    if (check_vector(s.acc_m_s2, 1e-3, p_.input.max_acc_m_s2, cnt_) &&
        stream_dt(s.t_host_ns, st_.acc_timing, dt_s)) {
      ++cnt_.acc_ok;
      update_acc(s.acc_m_s2, dt_s);
    }
  }
  if (s.has(kFieldMag)) {
    if (check_vector(s.mag_uT, 1e-6, p_.input.max_mag_uT, cnt_) &&
        stream_dt(s.t_host_ns, st_.mag_timing, dt_s)) {
      ++cnt_.mag_ok;
      update_mag(s.mag_uT, dt_s);
    }
  }
}

// Strapdown: the rest test's gyro part, then the gyro integrated over the period.
void AttitudeFilter::update_gyr(const Eigen::Vector3d& gyr, double dt_s) {
  update_rest_gyr(gyr);
  st_.strapdown.last_gyr_rad_s = gyr;
  if (dt_s <= 0) return;  // first sample: nothing to integrate yet
  const double t = std::min(dt_s, p_.input.max_gap_s);
  // Exact quaternion exponential of the bias- and gain-corrected rate held over the period.
  Eigen::Vector3d w = gyr - st_.bias.rad_s;
  if (p_.gyr_gain.sigma_init > 0) {
    w -= st_.gyr_gain.matrix() * w;
  }
  const double n = w.norm();
  const double angle = n * t;
  if (angle > 1e-12) {
    const double c = std::cos(angle / 2), sn = std::sin(angle / 2) / n;
    const Eigen::Quaterniond dq(c, sn * w.x(), sn * w.y(), sn * w.z());
    st_.strapdown.q_gyr = st_.strapdown.q_gyr * dq;
    st_.strapdown.q_gyr.normalize();
  }
}

// Rest detection, gyro part: deviation from the low-passed rate.
void AttitudeFilter::update_rest_gyr(const Eigen::Vector3d& gyr) {
  const double ts = c_.gyr_ts_s;
  const auto& lp = st_.rest.gyr_lp.step(gyr.data(), c_.rest_gyr_lp, p_.rest.filter_tau_s, ts);
  st_.rest.last_gyr_lp = Eigen::Vector3d(lp[0], lp[1], lp[2]);
  st_.rest.dev_gyr2 = (gyr - st_.rest.last_gyr_lp).squaredNorm();
  const double clip = p_.bias.clip_deg_s * kRadPerDeg;
  if (st_.rest.dev_gyr2 >=
          (p_.rest.th_gyr_deg_s * kRadPerDeg) * (p_.rest.th_gyr_deg_s * kRadPerDeg) ||
      st_.rest.last_gyr_lp.cwiseAbs().maxCoeff() > clip) {
    st_.rest.t_s = 0;
    st_.rest.at_rest = false;
  }
}

// Acc: the rest test's acc part, the inclination, and every bias_decim samples the bias (and
// gain) Kalman filters from the summed inclination corrections.
void AttitudeFilter::update_acc(const Eigen::Vector3d& acc, double dt_s) {
  (void)dt_s;
  update_rest_acc(acc);
  if (!update_inclination(acc)) return;
  st_.bias.corr_sum += st_.inclination.last_acc_earth.head<2>();
  st_.gyr_gain.gyr_sum_rad_s += st_.strapdown.last_gyr_rad_s;
  if (++st_.bias.n >= c_.bias_decim) {
    update_bias(Eigen::Vector3d(st_.bias.corr_sum.x(), st_.bias.corr_sum.y(), 1.0), c_.bias_ts_s);
    st_.bias.n = 0;
    st_.bias.corr_sum.setZero();
    st_.gyr_gain.gyr_sum_rad_s.setZero();
  }
}

// Rest detection, acc part: rest once both deviations stayed small for rest.min_t_s.
void AttitudeFilter::update_rest_acc(const Eigen::Vector3d& acc) {
  const double ts = c_.acc_ts_s;
  const auto& alp = st_.rest.acc_lp.step(acc.data(), c_.rest_acc_lp, p_.rest.filter_tau_s, ts);
  st_.rest.dev_acc2 = (acc - Eigen::Vector3d(alp[0], alp[1], alp[2])).squaredNorm();
  const double thg = p_.rest.th_gyr_deg_s * kRadPerDeg, tha = p_.rest.th_acc_m_s2;
  if (st_.rest.dev_gyr2 >= thg * thg || st_.rest.dev_acc2 >= tha * tha ||
      st_.rest.last_gyr_lp.cwiseAbs().maxCoeff() > p_.bias.clip_deg_s * kRadPerDeg) {
    st_.rest.t_s = 0;
    st_.rest.at_rest = false;
  } else {
    st_.rest.t_s += ts;
    if (st_.rest.t_s >= p_.rest.min_t_s) st_.rest.at_rest = true;
  }
}

// Inclination: acc low-passed in the almost-inertial frame, then into the 6D earth frame; the
// shortest rotation taking it onto +z is applied to q_acc. False (nothing changed) when the
// low-passed acc has no direction; else its direction is last_acc_earth.
bool AttitudeFilter::update_inclination(const Eigen::Vector3d& acc) {
  const double ts = c_.acc_ts_s;
  const Eigen::Vector3d acc_i = st_.strapdown.q_gyr * acc;
  const auto& f =
      st_.inclination.acc_lp.step(acc_i.data(), c_.acc_lp, p_.inclination.tau_acc_s, ts);
  const Eigen::Vector3d acc_f(f[0], f[1], f[2]);
  Eigen::Vector3d acc_e = st_.inclination.q_acc * acc_f;
  const double an = acc_e.norm();
  if (!(an > 1e-9)) return false;
  acc_e /= an;
  st_.inclination.last_acc_earth = acc_e;
  // Shortest rotation taking acc_e onto +z, applied fully.
  const double qw = std::sqrt(std::max((acc_e.z() + 1.0) / 2.0, 0.0));
  Eigen::Quaterniond qc;
  if (qw > 1e-6)
    qc = Eigen::Quaterniond(qw, 0.5 * acc_e.y() / qw, -0.5 * acc_e.x() / qw, 0);
  else
    qc = Eigen::Quaterniond(0, 1, 0, 0);
  st_.inclination.q_acc = qc * st_.inclination.q_acc;
  st_.inclination.q_acc.normalize();
  return true;
}

// acc_e holds the horizontal inclination corrections summed over the last ts seconds.
void AttitudeFilter::update_bias(const Eigen::Vector3d& acc_e, double ts) {
  if (!st_.bias.p_init) {
    st_.bias.p = Eigen::Matrix3d::Identity() * c_.bias_p0;
    st_.bias.p_init = true;
  }
  const Eigen::Matrix3d r6 = (st_.inclination.q_acc * st_.strapdown.q_gyr).toRotationMatrix();
  Eigen::Matrix3d r_lp = Eigen::Matrix3d::Identity();
  Eigen::Vector2d rb_lp = Eigen::Vector2d::Zero();
  const bool gain_on = p_.gyr_gain.sigma_init > 0 && p_.bias.motion_est;
  // The error the current estimates remove: bias plus gain times the block's mean rate.
  Eigen::Vector3d b_applied = st_.bias.rad_s;
  if (gain_on) {
    const Eigen::Vector3d w = st_.gyr_gain.gyr_sum_rad_s / c_.bias_decim - st_.bias.rad_s;
    b_applied += st_.gyr_gain.matrix() * w;
    update_gain_regressor(r6, w, ts);
  }
  const Eigen::Matrix<double, 2, 9>& reg = st_.gyr_gain.reg;
  if (p_.bias.motion_est) {
    // Row-major copy so the 9 channels are the rows of R.
    double rr[9];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        rr[3 * i + j] = r6(i, j);
    const auto& rl = st_.bias.motion_r_lp.step(rr, c_.bias_lp, p_.inclination.tau_acc_s, ts);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        r_lp(i, j) = rl[3 * i + j];
    const double rb[2] = {r6.row(0).dot(b_applied), r6.row(1).dot(b_applied)};
    const auto& bl = st_.bias.motion_bias_lp.step(rb, c_.bias_lp, p_.inclination.tau_acc_s, ts);
    rb_lp = Eigen::Vector2d(bl[0], bl[1]);
  }
  Eigen::Vector3d e, w;
  Eigen::Matrix3d cm;
  const Eigen::Vector3d& b = st_.bias.rad_s;
  if (st_.rest.at_rest && p_.bias.rest_est) {
    e = st_.rest.last_gyr_lp - b;
    cm = Eigen::Matrix3d::Identity();
    w.setConstant(c_.bias_rest_w);
  } else if (p_.bias.motion_est) {
    e.x() = -acc_e.y() / ts + rb_lp.x() - r_lp.row(0).dot(b);
    e.y() = acc_e.x() / ts + rb_lp.y() - r_lp.row(1).dot(b);
    e.z() = -r_lp.row(2).dot(b);
    if (gain_on) {
      e.head<2>() -= reg * st_.gyr_gain.g;
      if (++st_.gyr_gain.n >= c_.gain_decim) {
        st_.gyr_gain.n = 0;
        const double clip = p_.bias.clip_deg_s * kRadPerDeg;
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
    if (st_.bias.p(i, i) < c_.bias_p0) st_.bias.p(i, i) += c_.bias_v;
  if (w.x() < 0) return;
  const double clip = p_.bias.clip_deg_s * kRadPerDeg;
  e = e.cwiseMax(-clip).cwiseMin(clip);
  const Eigen::Matrix3d s = cm * st_.bias.p * cm.transpose() + Eigen::Matrix3d(w.asDiagonal());
  const Eigen::Matrix3d k = st_.bias.p * cm.transpose() * s.inverse();
  st_.bias.rad_s = (st_.bias.rad_s + k * e).cwiseMax(-clip).cwiseMin(clip);
  st_.bias.p -= k * cm * st_.bias.p;
}

// Regressor of G (row-major entries ij) in the horizontal rows r: R_ri w_j (w: the block's mean
// bias-corrected rate), summed and low-passed every gain_reg_decim bias steps (about 25 Hz;
// tau_acc is seconds).
void AttitudeFilter::update_gain_regressor(const Eigen::Matrix3d& r6, const Eigen::Vector3d& w,
                                           double ts) {
  for (int r = 0; r < 2; ++r)
    for (int i = 0; i < 3; ++i)
      st_.gyr_gain.reg_sum.block<1, 3>(r, 3 * i) += r6(r, i) * w.transpose();
  if (++st_.gyr_gain.reg_n >= c_.gain_reg_decim) {
    double g[18];
    const double inv = 1.0 / st_.gyr_gain.reg_n;
    for (int r = 0; r < 2; ++r)
      for (int k = 0; k < 9; ++k)
        g[9 * r + k] = st_.gyr_gain.reg_sum(r, k) * inv;
    const auto& gl = st_.gyr_gain.reg_lp.step(g, c_.gain_reg_lp, p_.inclination.tau_acc_s,
                                              ts * c_.gain_reg_decim);
    for (int r = 0; r < 2; ++r)
      for (int k = 0; k < 9; ++k)
        st_.gyr_gain.reg(r, k) = gl[9 * r + k];
    st_.gyr_gain.reg_sum.setZero();
    st_.gyr_gain.reg_n = 0;
  }
}

// Gyro-gain Kalman update: residual = reg * (G - G_est) + bias error + noise (rad/s).
void AttitudeFilter::update_gain(const Eigen::Vector2d& residual,
                                 const Eigen::Matrix<double, 2, 9>& reg,
                                 const Eigen::Matrix3d& r_lp) {
  if (!st_.gyr_gain.p_init) {
    st_.gyr_gain.p = Eigen::Matrix<double, 9, 9>::Identity() * c_.gain_p0;
    st_.gyr_gain.p_init = true;
  }
  for (int i = 0; i < 9; ++i)
    if (st_.gyr_gain.p(i, i) < c_.gain_p0) st_.gyr_gain.p(i, i) += c_.gain_v;
  // Measurement noise: the motion update's plus the current bias uncertainty.
  const Eigen::Matrix<double, 2, 3> cb = r_lp.topRows<2>() * (0.01 * kRadPerDeg);
  Eigen::Matrix2d s = cb * st_.bias.p * cb.transpose();
  s.diagonal().array() += c_.gain_w;
  const Eigen::Matrix<double, 9, 2> ph = st_.gyr_gain.p * reg.transpose();
  s += reg * ph;
  const Eigen::Matrix<double, 9, 2> k = ph * s.inverse();
  const double clip = p_.gyr_gain.clip;
  st_.gyr_gain.g = (st_.gyr_gain.g + k * residual).cwiseMax(-clip).cwiseMin(clip);
  st_.gyr_gain.p -= k * ph.transpose();
}

double AttitudeFilter::field_deviation2(double norm, double dip, double ref_norm,
                                        double ref_dip) const {
  const double dn = (norm - ref_norm) / (p_.mag_dist.norm_th * ref_norm);
  const double dd = (dip - ref_dip) / (p_.mag_dist.dip_th_deg * kRadPerDeg);
  return dn * dn + dd * dd;
}

double AttitudeFilter::mag_latency_s() const {
  return p_.mag_latency.tau_s > 0
             ? st_.mag_latency.latency_s(p_.mag_latency.min_rate_deg_s * kRadPerDeg,
                                         p_.mag_latency.max_s)
             : 0.0;
}

// A field sample: hard iron, into the 6D frame (latency-compensated), disturbance tests,
// heading.
void AttitudeFilter::update_mag(const Eigen::Vector3d& mag_raw, double dt_s) {
  const Eigen::Quaterniond q6 = st_.inclination.q_acc * st_.strapdown.q_gyr;
  if (p_.hard_iron.tau_s > 0) update_hard_iron(mag_raw, q6, dt_s);
  const Eigen::Vector3d m_e = mag_to_earth(mag_raw - st_.hard_iron.applied_uT, q6);
  if (p_.mag_dist.rejection) update_mag_disturbance(m_e);
  update_heading(m_e, dt_s);
}

// Hard-iron estimator (decimated to hard_iron.step_s), fed with the latency-compensated raw
// field; then the choice of the offset subtracted.
void AttitudeFilter::update_hard_iron(const Eigen::Vector3d& mag_raw, const Eigen::Quaterniond& q6,
                                      double dt_s) {
  HardIronState& h = st_.hard_iron;
  h.dt_s += dt_s > 0 ? dt_s : c_.mag_ts_s;
  if (++h.n < c_.hard_iron_decim) return;
  const double lat_s = mag_latency_s();
  const Eigen::Vector3d w = st_.strapdown.last_gyr_rad_s - st_.bias.rad_s;
  const Eigen::Vector3d m_c = mag_raw - lat_s * w.cross(mag_raw - h.est.used_uT);
  const Eigen::Matrix3d r6 = q6.toRotationMatrix();
  h.est.step(m_c, r6, std::min(h.dt_s, 1.0), st_.mag_dist.ref_norm, c_.hard_iron);
  h.n = 0;
  h.dt_s = 0;
  select_hard_iron(r6 * m_c, r6 * (m_c - h.est.used_uT));
}

// Applies the gated offset only while it explains a disturbance: the squared norm/dip
// deviations from the reference (relative to the thresholds) without and with it; or, with a
// lower significance, while the estimator's innovations have stayed consistent.
void AttitudeFilter::select_hard_iron(const Eigen::Vector3d& m_raw_e,
                                      const Eigen::Vector3d& m_corr_e) {
  HardIronState& hs = st_.hard_iron;
  const HardIronEstimator& h = hs.est;
  const double ref_norm = st_.mag_dist.ref_norm;
  bool consistent = false;
  if (p_.hard_iron.consistent_nis > 0) {
    if (h.restarts != hs.restarts_seen || !(h.nis < p_.hard_iron.consistent_nis))
      hs.consistent_s = 0;
    else
      hs.consistent_s += c_.hard_iron_decim * c_.mag_ts_s;
    hs.restarts_seen = h.restarts;
    consistent = ref_norm > 0 && hs.consistent_s >= p_.hard_iron.consistent_s;
  }
  if (p_.hard_iron.select_margin <= 0) {
    hs.weight = 1;
  } else if (ref_norm <= 0 || h.used_uT.isZero()) {
    // Nothing to compare with before a reference field exists (a field that varies around
    // a magnet at start-up must not be "explained" by an offset), or nothing to apply.
    hs.select = 0;
    hs.weight = 0;
  } else {
    auto score = [&](const Eigen::Vector3d& m) {
      const double n = m.norm();
      if (!(n > 0)) return 0.0;
      return std::min(field_deviation2(n, dip_rad(m, n), ref_norm, st_.mag_dist.ref_dip), 25.0);
    };
    hs.select += c_.k_hard_iron_select * (score(m_raw_e) - score(m_corr_e) - hs.select);
    hs.weight = std::clamp(hs.select / p_.hard_iron.select_margin, 0.0, 1.0);
  }
  hs.applied_uT = hs.weight * h.used_uT;
  hs.applied_consistent = false;
  if (consistent && h.used_consistent_uT.norm() > hs.applied_uT.norm()) {
    hs.applied_uT = h.used_consistent_uT;
    hs.applied_consistent = true;
  }
}

// Into the 6D earth frame, compensated for the latency behind the gyro: a field read L late
// is the current one rotated by w L, so v = q6 (w x m) is its rate of change there.
Eigen::Vector3d AttitudeFilter::mag_to_earth(const Eigen::Vector3d& mag,
                                             const Eigen::Quaterniond& q6) {
  Eigen::Vector3d m_e = q6 * mag;
  if (p_.mag_latency.tau_s > 0) {
    const Eigen::Vector3d v_e = q6 * (st_.strapdown.last_gyr_rad_s - st_.bias.rad_s).cross(mag);
    st_.mag_latency.step(m_e, v_e, c_.k_latency_hp, c_.k_latency);
    m_e -= mag_latency_s() * v_e;
  }
  return m_e;
}

// Disturbance tests: the smoothed norm and dip against the reference (tracked while
// undisturbed), and a candidate for a new reference (self-consistent while rotating).
void AttitudeFilter::update_mag_disturbance(const Eigen::Vector3d& m_e) {
  MagDisturbanceState& d = st_.mag_dist;
  const MagDisturbanceParams& p = p_.mag_dist;
  const double ts = c_.mag_ts_s;
  const double n = m_e.norm();
  const double nd[2] = {n, dip_rad(m_e, n)};
  const auto& f = d.norm_dip_lp.step(nd, c_.mag_norm_dip_lp, p.current_tau_s, ts);
  d.norm_dip[0] = f[0];
  d.norm_dip[1] = f[1];
  const double norm = f[0], dip = f[1];
  const double dip_th = p.dip_th_deg * kRadPerDeg;
  if (std::abs(norm - d.ref_norm) < p.norm_th * d.ref_norm && std::abs(dip - d.ref_dip) < dip_th) {
    d.undisturbed_t_s += ts;
    if (d.undisturbed_t_s >= p.min_undisturbed_time_s) {
      d.disturbed = false;
      d.ref_norm += c_.k_mag_ref * (norm - d.ref_norm);
      d.ref_dip += c_.k_mag_ref * (dip - d.ref_dip);
    }
  } else {
    d.undisturbed_t_s = 0;
    d.disturbed = true;
  }
  if (std::abs(norm - d.cand_norm) < p.norm_th * d.cand_norm &&
      std::abs(dip - d.cand_dip) < dip_th) {
    // A new field replacing a known one must be seen while rotating (a static local
    // disturbance stays self-consistent at rest); the very first field needs no rotation.
    if (d.ref_norm == 0 || st_.rest.last_gyr_lp.norm() >= p.new_min_gyr_deg_s * kRadPerDeg)
      d.cand_t_s += ts;
    d.cand_age_s += ts;
    d.cand_norm += c_.k_mag_ref * (norm - d.cand_norm);
    d.cand_dip += c_.k_mag_ref * (dip - d.cand_dip);
    if (d.disturbed &&
        (d.cand_t_s >= p.new_time_s || (d.ref_norm == 0 && d.cand_t_s >= p.new_first_time_s))) {
      if (!d.have_ref) end_mag_startup();
      d.ref_norm = d.cand_norm;
      d.ref_dip = d.cand_dip;
      d.disturbed = false;
      d.undisturbed_t_s = p.min_undisturbed_time_s;
    }
  } else {
    d.cand_t_s = 0;
    d.cand_age_s = 0;
    d.cand_norm = norm;
    d.cand_dip = dip;
  }
}

// Kalman heading. Predict: the heading drifts by the nominal process noise plus what the
// gyro-bias uncertainty allows. Update with the field's heading in the 6D frame, at the gain
// the rejection and start-up rules leave; Joseph form (valid for those gains as well).
void AttitudeFilter::update_heading(const Eigen::Vector3d& m_e, double dt_s) {
  HeadingState& h = st_.heading;
  const double err = wrap_pi(std::atan2(m_e.x(), m_e.y()) - h.delta_rad);
  const double sb2 = st_.bias.p(2, 2) * (0.01 * kRadPerDeg) * (0.01 * kRadPerDeg);
  h.delta_var_rad2 += (c_.heading_q_rad2_s + sb2) * (dt_s > 0 ? dt_s : c_.mag_ts_s);  // real gap
  const double r = heading_measurement_var();
  const double k = heading_gain(h.delta_var_rad2 / (h.delta_var_rad2 + r));
  h.delta_rad = wrap_pi(h.delta_rad + k * err);
  h.delta_var_rad2 = (1 - k) * (1 - k) * h.delta_var_rad2 + k * k * r;
  h.q_delta = heading_quat(h.delta_rad);
}

// Nominal (steady state = tau_mag), inflated by the squared disturbance indicators, each
// relative to its threshold, and by the rejection time not yet repaid.
double AttitudeFilter::heading_measurement_var() const {
  const MagDisturbanceState& d = st_.mag_dist;
  double r = c_.heading_r0_rad2;
  if (p_.mag_dist.rejection && (d.ref_norm > 0 || d.cand_norm > 0)) {
    // Deviations from the reference, or before one exists from the candidate.
    const bool ref = d.ref_norm > 0;
    const double rn = ref ? d.ref_norm : d.cand_norm;
    const double rd = ref ? d.ref_dip : d.cand_dip;
    double score =
        p_.mag_dist.trust_weight * field_deviation2(d.norm_dip[0], d.norm_dip[1], rn, rd);
    score += d.reject_t_s / p_.heading.tau_mag_s;
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
  const double ts = c_.mag_ts_s;
  MagDisturbanceState& d = st_.mag_dist;
  HeadingState& h = st_.heading;
  bool use_init = true;
  if (p_.mag_dist.rejection) {
    if (!d.have_ref) {
      use_init = false;
      if (!h.set)
        k = 1;
      else if (d.cand_age_s < p_.mag_dist.min_undisturbed_time_s)
        k = 0;
      h.set = true;
    } else if (d.disturbed) {
      use_init = false;
      if (d.reject_t_s <= p_.mag_dist.max_rejection_time_s) {
        d.reject_t_s += ts;
        k = 0;
      } else {
        k = std::min(k, c_.k_mag) / p_.mag_dist.rejection_factor;  // backstop: nominal gain at most
      }
    } else {
      d.reject_t_s = std::max(d.reject_t_s - p_.mag_dist.rejection_factor * ts, 0.0);
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
      st_.heading.delta_var_rad2 / (st_.heading.delta_var_rad2 + c_.heading_r0_rad2);
}

// Predicted to the newest gyro sample (the magnetometer may be slower or missing).
double AttitudeFilter::heading_sigma_rad() const {
  if (!st_.mag_timing.have) return std::numbers::pi;
  const double since_mag_s =
      std::max(static_cast<double>(st_.gyr_timing.t_ns - st_.mag_timing.t_ns), 0.0) * 1e-9;
  const double sb2 = st_.bias.p(2, 2) * (0.01 * kRadPerDeg) * (0.01 * kRadPerDeg);
  return std::sqrt(
      std::max(st_.heading.delta_var_rad2 + (c_.heading_q_rad2_s + sb2) * since_mag_s, 0.0));
}

FilterOutput AttitudeFilter::output() const {
  const bool have_mag = st_.mag_timing.have;
  const bool rejection = p_.mag_dist.rejection;
  FilterOutput o;
  o.q_earth_sensor_6d = st_.inclination.q_acc * st_.strapdown.q_gyr;
  o.q_earth_sensor = have_mag ? st_.heading.q_delta * o.q_earth_sensor_6d : o.q_earth_sensor_6d;
  o.gyro_bias_rad_s = st_.bias.rad_s;
  o.heading_sigma_rad = heading_sigma_rad();
  o.mag_heading_rad =
      have_mag && o.heading_sigma_rad <= FilterOutput::kSettledHeadingSigmaDeg * kRadPerDeg
          ? st_.heading.delta_rad
          : std::numeric_limits<double>::quiet_NaN();
  o.flags.at_rest = st_.rest.at_rest;
  o.flags.mag_disturbed = have_mag && st_.mag_dist.have_ref && rejection && st_.mag_dist.disturbed;
  o.flags.mag_no_reference = have_mag && rejection && !st_.mag_dist.have_ref;
  o.flags.mag_reference = have_mag && st_.mag_dist.have_ref;
  o.hard_iron_uT = st_.hard_iron.applied_uT;
  o.hard_iron_sigma_uT = st_.hard_iron.est.offset_sigma_uT;
  return o;
}

}  // namespace mocap
