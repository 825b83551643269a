// AttitudeFilter: setup, sample timing, and the gyro and acc stages (strapdown, rest,
// inclination, gyro bias and gain Kalman filters); the read API output(). The magnetometer
// stages are in attitude_filter_mag.cpp. Equations in docs/filter.md.
#include "mocap/filter/attitude_filter.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "mocap/core/units.hpp"
#include "mocap/filter/filter_constants.hpp"
#include "mocap/filter/input_check.hpp"
#include "mocap/filter/small_angle.hpp"

namespace mocap {
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
  c_.ts.gyr_s = st_.gyr_timing.ts_nom_s > 0 ? st_.gyr_timing.ts_nom_s : fallback;
  c_.ts.acc_s = st_.acc_timing.ts_nom_s > 0 ? st_.acc_timing.ts_nom_s : c_.ts.gyr_s;
  c_.ts.mag_s = st_.mag_timing.ts_nom_s > 0 ? st_.mag_timing.ts_nom_s : c_.ts.acc_s;

  c_.acc_lp = butterworth(p_.inclination.tau_acc_s, c_.ts.acc_s);
  c_.rest.gyr_lp = butterworth(kRestFilterTau_s, c_.ts.gyr_s);
  c_.rest.acc_lp = butterworth(kRestFilterTau_s, c_.ts.acc_s);
  c_.mag_dist.norm_dip_lp = butterworth(kMagCurrentTau_s, c_.ts.mag_s);
  c_.heading.k_mag = gain_from_tau(p_.heading.tau_mag_s, c_.ts.mag_s);
  // Kalman heading: q = sigma^2 / tau, r = sigma^2 tau / T gives the time constant tau_mag
  // and the steady-state one-sigma heading_sigma_deg in an undisturbed field, at any rate.
  const double sh2 = sq(p_.heading.sigma_deg * kRadPerDeg);
  c_.heading.q_rad2_s = sh2 / std::max(p_.heading.tau_mag_s, 1e-9);
  c_.heading.r0_rad2 = sh2 * p_.heading.tau_mag_s / c_.ts.mag_s;
  c_.mag_dist.k_ref = gain_from_tau(p_.mag_dist.ref_tau_s, c_.ts.mag_s);
  c_.mag_dist.head_th2_rad2 = sq(p_.mag_dist.heading_th_deg * kRadPerDeg);
  c_.mag_dist.inv_head_th2_rad2 = 1.0 / c_.mag_dist.head_th2_rad2;
  c_.mag_dist.inv_dip_th_rad = 1.0 / (p_.mag_dist.dip_th_deg * kRadPerDeg);
  c_.heading.inv_tau_mag_s = 1.0 / p_.heading.tau_mag_s;
  c_.mag_dist.k_head = gain_from_tau(kHeadingDevTau_s, c_.ts.mag_s);
  // Hard-iron estimator: fixed period in seconds; variances relative to the field norm.
  c_.hard_iron.decim = std::max(1, static_cast<int>(std::lround(kHardIronStep_s / c_.ts.mag_s)));
  c_.hard_iron.est.p0_offset_rel2 = sq(kHardIronSigma0);
  c_.hard_iron.est.q_offset_rel2_s =
      c_.hard_iron.est.p0_offset_rel2 / std::max(p_.hard_iron.tau_s, 1e-9);
  c_.hard_iron.est.q_field_rel2_s = sq(kHardIronFieldRw_deg * kRadPerDeg);
  c_.hard_iron.est.r_rel2 = sq(kHardIronNoise);
  c_.hard_iron.est.gate_rel2 = sq(p_.hard_iron.gate);
  c_.hard_iron.est.min_offset_rel = kHardIronMinOffset;
  c_.hard_iron.est.min_sigmas = kHardIronMinSigmas;
  c_.hard_iron.est.k_nis = gain_from_tau(kHardIronNisTau_s, c_.hard_iron.decim * c_.ts.mag_s);
  c_.hard_iron.est.nis_max = kHardIronNisMax;
  c_.hard_iron.k_select = gain_from_tau(kHardIronSelectTau_s, c_.hard_iron.decim * c_.ts.mag_s);
  c_.mag_latency.k = gain_from_tau(p_.mag_latency.tau_s, c_.ts.mag_s);
  c_.upset_acc_lp = butterworth(kUpsetTau_s, c_.ts.acc_s);
  c_.upset_mag_lp = butterworth(kUpsetTau_s, c_.ts.mag_s);
  c_.upset_gyr_rad_s = p_.upset.gyr_deg_s * kRadPerDeg;
  c_.mag_latency.k_hp = gain_from_tau(kMagLatencyHpTau_s, c_.ts.mag_s);

  // The bias KF runs decimated to about 100 Hz: bias changes over minutes.
  c_.bias.decim = std::max(1, static_cast<int>(std::lround(0.01 / c_.ts.acc_s)));
  c_.bias.ts_s = c_.bias.decim * c_.ts.acc_s;
  c_.bias.lp = butterworth(p_.inclination.tau_acc_s, c_.bias.ts_s);
  // Bias KF in units of (0.01 deg/s)^2: uncertainty grows by 0.1 deg/s per forgetting time.
  c_.bias.p0 = sq(kBiasSigmaInit_deg_s * 100.0);
  c_.bias.v = sq(0.1 * 100.0) * c_.bias.ts_s / p_.bias.forgetting_time_s;
  const double p_motion = sq(p_.bias.sigma_motion_deg_s * 100.0);
  c_.bias.motion_w = sq(p_motion) / c_.bias.v + p_motion;
  c_.bias.vertical_w = c_.bias.motion_w / kBiasVerticalForgetting;
  const double p_rest = sq(p_.bias.sigma_rest_deg_s * 100.0);
  c_.bias.rest_w = sq(p_rest) / c_.bias.v + p_rest;
  // Gyro-gain KF: every gain_decim bias steps (about 10 Hz; the residual is low-passed with
  // tau_acc, so sub-sampling it loses little), in gain units; the measurement noise is the
  // motion bias update's per step, in (rad/s)^2.
  c_.gyr_gain.decim = std::max(1, static_cast<int>(std::lround(0.1 / c_.bias.ts_s)));
  c_.gyr_gain.reg_decim = std::max(1, static_cast<int>(std::lround(0.04 / c_.bias.ts_s)));
  c_.gyr_gain.reg_lp = butterworth(p_.inclination.tau_acc_s, c_.gyr_gain.reg_decim * c_.bias.ts_s);
  const double gain_ts = c_.gyr_gain.decim * c_.bias.ts_s;
  c_.gyr_gain.p0 = sq(p_.gyr_gain.sigma_init);
  c_.gyr_gain.v = sq(1e-3) * gain_ts / kGyrGainForgettingTime_s;
  c_.gyr_gain.w = c_.bias.motion_w * sq(0.01 * kRadPerDeg);
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
  // Re-derive coefficients when this stream's tracked period moved more than 2 % from the one
  // in use. Only this stream's can have moved: every other stream's was checked (and the
  // coefficients refreshed) when it last changed, and coefficients change only here.
  const double used = &timing == &st_.gyr_timing   ? c_.ts.gyr_s
                      : &timing == &st_.acc_timing ? c_.ts.acc_s
                                                   : c_.ts.mag_s;
  if (ts_nom > 0 && std::abs(ts_nom - used) > 0.02 * used) refresh_coeffs();
  return true;
}

[[gnu::flatten]] void AttitudeFilter::update(const ImuSample& s) {
  double dt_s = 0;
  if (s.has(kFieldGyr)) {
    if (check_vector(s.gyr_rad_s, 0.0, kMaxGyr_rad_s, cnt_) &&
        stream_dt(s.t_host_ns, st_.gyr_timing, dt_s)) {
      ++cnt_.gyr_ok;
      if (p_.upset.enabled &&
          ((s.flags & kFlagGyrClipped) || s.gyr_rad_s.cwiseAbs().maxCoeff() >= c_.upset_gyr_rad_s))
        note_clipped_gyr();
      update_gyr(s.gyr_rad_s, dt_s);
    }
  }
  if (s.has(kFieldAcc)) {
    if (check_vector(s.acc_m_s2, 1e-3, kMaxAcc_m_s2, cnt_) &&
        stream_dt(s.t_host_ns, st_.acc_timing, dt_s)) {
      ++cnt_.acc_ok;
      update_acc(s.acc_m_s2, dt_s);
    }
  }
  if (s.has(kFieldMag)) {
    if (check_vector(s.mag_uT, 1e-6, kMaxMag_uT, cnt_) &&
        stream_dt(s.t_host_ns, st_.mag_timing, dt_s)) {
      ++cnt_.mag_ok;
      update_mag(s.mag_uT, dt_s);
    }
  }
}

// Strapdown: the rest test's gyro part, then the gyro integrated over the period. Across a
// gap (a period over twice the nominal: samples lost) the rate is taken as changing in a
// straight line from the last sample to this one (the mean of the two held over the gap); a
// gap over kMaxGap_s is not integrated at all: the rotation in it is unknown, and a guess
// from either end only adds to it (every sensor silent 0.3 / 0.5 / 3 s in CMU 6D motion: the
// joints afterwards 18.4 / 23.3 / 28.0 deg holding the newest rate 0.25 s, 14.3 / 16.6 / 23.2
// integrating nothing; docs/filter.md).
void AttitudeFilter::update_gyr(const Eigen::Vector3d& gyr, double dt_s) {
  update_rest_gyr(gyr);
  const Eigen::Vector3d before = st_.strapdown.last_gyr_rad_s;
  st_.strapdown.last_gyr_rad_s = gyr;
  const bool gap = dt_s > 2 * c_.ts.gyr_s;
  if (dt_s <= 0 || (gap && dt_s > kMaxGap_s)) return;  // first sample, or too long to bridge
  // Exact quaternion exponential of the bias- and gain-corrected rate held over the period.
  Eigen::Vector3d w = (gap ? 0.5 * (gyr + before) : gyr) - st_.bias.rad_s;
  if (p_.gyr_gain.sigma_init > 0) {
    w -= st_.gyr_gain.matrix() * w;
  }
  // Half the angle turned, squared: (|w| dt / 2)^2. Small angles (nearly every sample) take the
  // series of cos and sin(x)/x, without square root, sincos or division.
  const double half2 = w.squaredNorm() * (dt_s * dt_s) * 0.25;
  if (half2 > 0.25e-24) {  // angle > 1e-12 rad
    double c, sn;          // cos(angle / 2), sin(angle / 2) / |w|
    if (half2 <= kSmallAngle2) {
      c = cos_small(half2);
      sn = 0.5 * dt_s * sinc_small(half2);
    } else {
      const double n = w.norm(), angle = n * dt_s;
      c = std::cos(angle / 2);
      sn = std::sin(angle / 2) / n;
    }
    const Eigen::Quaterniond dq(c, sn * w.x(), sn * w.y(), sn * w.z());
    st_.strapdown.q_gyr = st_.strapdown.q_gyr * dq;
    renormalize(st_.strapdown.q_gyr);
  }
}

// Rest detection, gyro part: deviation from the low-passed rate.
void AttitudeFilter::update_rest_gyr(const Eigen::Vector3d& gyr) {
  const double ts = c_.ts.gyr_s;
  const auto& lp = st_.rest.gyr_lp.step(gyr.data(), c_.rest.gyr_lp, kRestFilterTau_s, ts);
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
  if (st_.upset.checking) check_upset(acc);  // nothing to do while nothing was clipped
  if (!update_inclination(acc)) return;
  st_.bias.corr_sum += st_.inclination.last_acc_earth.head<2>();
  st_.gyr_gain.gyr_sum_rad_s += st_.strapdown.last_gyr_rad_s;
  if (++st_.bias.n >= c_.bias.decim) {
    update_bias(Eigen::Vector3d(st_.bias.corr_sum.x(), st_.bias.corr_sum.y(), 1.0), c_.bias.ts_s);
    st_.bias.n = 0;
    st_.bias.corr_sum.setZero();
    st_.gyr_gain.gyr_sum_rad_s.setZero();
  }
}

// Rest detection, acc part: rest once both deviations stayed small for rest.min_t_s.
void AttitudeFilter::update_rest_acc(const Eigen::Vector3d& acc) {
  const double ts = c_.ts.acc_s;
  const auto& alp = st_.rest.acc_lp.step(acc.data(), c_.rest.acc_lp, kRestFilterTau_s, ts);
  st_.rest.dev_acc2 = (acc - Eigen::Vector3d(alp[0], alp[1], alp[2])).squaredNorm();
  const double thg = p_.rest.th_gyr_deg_s * kRadPerDeg, tha = p_.rest.th_acc_m_s2;
  if (st_.rest.dev_gyr2 >= thg * thg || st_.rest.dev_acc2 >= tha * tha ||
      st_.rest.last_gyr_lp.cwiseAbs().maxCoeff() > p_.bias.clip_deg_s * kRadPerDeg) {
    st_.rest.t_s = 0;
    st_.rest.at_rest = false;
  } else {
    if (!st_.bias.rest_seen) {  // until the first rest: the gyro summed from its first sample
      if (st_.rest.t_s == 0) {
        st_.rest.gyr_sum_rad_s.setZero();
        st_.rest.n = 0;
      }
      st_.rest.gyr_sum_rad_s += st_.strapdown.last_gyr_rad_s;
      ++st_.rest.n;
    }
    st_.rest.t_s += ts;
    if (st_.rest.t_s >= p_.rest.min_t_s) st_.rest.at_rest = true;
  }
}

// Inclination: acc low-passed in the almost-inertial frame, then into the 6D earth frame; the
// shortest rotation taking it onto +z is applied to q_acc. False (nothing changed) when the
// low-passed acc has no direction; else its direction is last_acc_earth.
bool AttitudeFilter::update_inclination(const Eigen::Vector3d& acc) {
  const double ts = c_.ts.acc_s;
  const Eigen::Vector3d acc_i = st_.strapdown.q_gyr * acc;
  const auto& f =
      st_.inclination.acc_lp.step(acc_i.data(), c_.acc_lp, p_.inclination.tau_acc_s, ts);
  const Eigen::Vector3d acc_f(f[0], f[1], f[2]);
  Eigen::Vector3d acc_e = st_.inclination.q_acc * acc_f;
  const double an = acc_e.norm();
  if (!(an > 1e-9)) return false;
  st_.inclination.last_acc_earth = acc_e * (1.0 / an);
  // Shortest rotation taking acc_e onto +z, applied fully: (|a| + a_z, a_y, -a_x, 0) normalised
  // (its squared norm is 2 |a| (|a| + a_z)); w = sqrt((1 + a_z / |a|) / 2) > 1e-6 unless upside
  // down.
  const double s = an + acc_e.z();
  Eigen::Quaterniond qc;
  if (s > 2e-12 * an) {
    const double inv = 1.0 / std::sqrt(2 * an * s);
    qc = Eigen::Quaterniond(s * inv, acc_e.y() * inv, -acc_e.x() * inv, 0);
  } else {
    qc = Eigen::Quaterniond(0, 1, 0, 0);
  }
  st_.inclination.q_acc = qc * st_.inclination.q_acc;
  renormalize(st_.inclination.q_acc);
  return true;
}

// acc_e holds the horizontal inclination corrections summed over the last ts seconds.
void AttitudeFilter::update_bias(const Eigen::Vector3d& acc_e, double ts) {
  if (!st_.bias.p_init) {
    st_.bias.p = Eigen::Matrix3d::Identity() * c_.bias.p0;
    st_.bias.p_init = true;
  }
  const Eigen::Matrix3d r6 = (st_.inclination.q_acc * st_.strapdown.q_gyr).toRotationMatrix();
  Eigen::Matrix3d r_lp = Eigen::Matrix3d::Identity();
  Eigen::Vector2d rb_lp = Eigen::Vector2d::Zero();
  const bool gain_on = p_.gyr_gain.sigma_init > 0 && p_.bias.motion_est;
  // The error the current estimates remove: bias plus gain times the block's mean rate.
  Eigen::Vector3d b_applied = st_.bias.rad_s;
  if (gain_on) {
    const Eigen::Vector3d w = st_.gyr_gain.gyr_sum_rad_s / c_.bias.decim - st_.bias.rad_s;
    b_applied += st_.gyr_gain.matrix() * w;
    update_gain_regressor(r6, w, ts);
  }
  const Eigen::Matrix<double, 2, 9>& reg = st_.gyr_gain.reg;
  if (p_.bias.motion_est) {
    // Row-major copy so the 9 channels are the rows of R (fixed-size copies, unrolled).
    using RowMajor3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
    const RowMajor3 rr = r6;
    const auto& rl = st_.bias.motion_r_lp.step(rr.data(), c_.bias.lp, p_.inclination.tau_acc_s, ts);
    r_lp = Eigen::Map<const RowMajor3>(rl.data());
    const double rb[2] = {r6.row(0).dot(b_applied), r6.row(1).dot(b_applied)};
    const auto& bl = st_.bias.motion_bias_lp.step(rb, c_.bias.lp, p_.inclination.tau_acc_s, ts);
    rb_lp = Eigen::Vector2d(bl[0], bl[1]);
  }
  Eigen::Vector3d e = Eigen::Vector3d::Zero(), w;
  Eigen::Matrix3d cm;
  const Eigen::Vector3d& b = st_.bias.rad_s;
  if (st_.rest.at_rest && p_.bias.rest_est) {
    cm = Eigen::Matrix3d::Identity();
    if (st_.bias.rest_seen) {
      e = st_.rest.last_gyr_lp - b;
      w.setConstant(c_.bias.rest_w);
    } else {
      // The first rest (a still start): its whole mean so far, from the rest's first sample
      // (not only from its detection, rest.min_t_s later), as one measurement weighing as
      // many rest updates as it spans: the bias and its uncertainty the rest updates would
      // reach only that much later.
      st_.bias.rest_seen = true;
      const double n = std::max(1, st_.rest.n);
      e = st_.rest.gyr_sum_rad_s / n - b;
      w.setConstant(c_.bias.rest_w * c_.bias.decim / n);
    }
  } else if (p_.bias.motion_est) {
    e.x() = -acc_e.y() / ts + rb_lp.x() - r_lp.row(0).dot(b);
    e.y() = acc_e.x() / ts + rb_lp.y() - r_lp.row(1).dot(b);
    e.z() = -r_lp.row(2).dot(b);
    if (gain_on) {
      e.head<2>() -= reg * st_.gyr_gain.g;
      if (++st_.gyr_gain.n >= c_.gyr_gain.decim) {
        st_.gyr_gain.n = 0;
        const double clip = p_.bias.clip_deg_s * kRadPerDeg;
        update_gain(e.head<2>().cwiseMax(-clip).cwiseMin(clip), reg, r_lp);
      }
    }
    cm = r_lp;
    w = Eigen::Vector3d(c_.bias.motion_w, c_.bias.motion_w, c_.bias.vertical_w);
  } else {
    w.setConstant(-1);
  }
  // Process noise while the uncertainty is below its initial value.
  for (int i = 0; i < 3; ++i)
    if (st_.bias.p(i, i) < c_.bias.p0) st_.bias.p(i, i) += c_.bias.v;
  if (w.x() < 0) return;
  const double clip = p_.bias.clip_deg_s * kRadPerDeg;
  e = e.cwiseMax(-clip).cwiseMin(clip);
  // P C^T once: S = C (P C^T) + W, K = (P C^T) S^-1, P -= K (P C^T)^T (= K C P, P symmetric).
  const Eigen::Matrix3d pct = st_.bias.p * cm.transpose();
  Eigen::Matrix3d s = cm * pct;
  s.diagonal() += w;
  const Eigen::Matrix3d k = pct * s.inverse();
  st_.bias.rad_s = (st_.bias.rad_s + k * e).cwiseMax(-clip).cwiseMin(clip);
  st_.bias.p.noalias() -= k * pct.transpose();
}

// Regressor of G (row-major entries ij) in the horizontal rows r: R_ri w_j (w: the block's mean
// bias-corrected rate), summed and low-passed every gain_reg_decim bias steps (about 25 Hz;
// tau_acc is seconds).
void AttitudeFilter::update_gain_regressor(const Eigen::Matrix3d& r6, const Eigen::Vector3d& w,
                                           double ts) {
  // Entry (r, 3 i + j) += R_ri w_j: per i a 2x3 outer product (fixed-size blocks, unrolled).
  Eigen::Matrix<double, 2, 9>& rs = st_.gyr_gain.reg_sum;
  rs.middleCols<3>(0) += r6.block<2, 1>(0, 0) * w.transpose();
  rs.middleCols<3>(3) += r6.block<2, 1>(0, 1) * w.transpose();
  rs.middleCols<3>(6) += r6.block<2, 1>(0, 2) * w.transpose();
  if (++st_.gyr_gain.reg_n >= c_.gyr_gain.reg_decim) {
    // Row-major: channel 9 r + k is entry (r, k).
    using RowMajor29 = Eigen::Matrix<double, 2, 9, Eigen::RowMajor>;
    const double inv = 1.0 / st_.gyr_gain.reg_n;
    const RowMajor29 g = st_.gyr_gain.reg_sum * inv;
    const auto& gl = st_.gyr_gain.reg_lp.step(g.data(), c_.gyr_gain.reg_lp,
                                              p_.inclination.tau_acc_s, ts * c_.gyr_gain.reg_decim);
    st_.gyr_gain.reg = Eigen::Map<const RowMajor29>(gl.data());
    st_.gyr_gain.reg_sum.setZero();
    st_.gyr_gain.reg_n = 0;
  }
}

// Gyro-gain Kalman update: residual = reg * (G - G_est) + bias error + noise (rad/s).
void AttitudeFilter::update_gain(const Eigen::Vector2d& residual,
                                 const Eigen::Matrix<double, 2, 9>& reg,
                                 const Eigen::Matrix3d& r_lp) {
  if (!st_.gyr_gain.p_init) {
    st_.gyr_gain.p = Eigen::Matrix<double, 9, 9>::Identity() * c_.gyr_gain.p0;
    st_.gyr_gain.p_init = true;
  }
  for (int i = 0; i < 9; ++i)
    if (st_.gyr_gain.p(i, i) < c_.gyr_gain.p0) st_.gyr_gain.p(i, i) += c_.gyr_gain.v;
  // Measurement noise: the motion update's plus the current bias uncertainty.
  const Eigen::Matrix<double, 2, 3> cb = r_lp.topRows<2>() * (0.01 * kRadPerDeg);
  Eigen::Matrix2d s = cb * st_.bias.p * cb.transpose();
  s.diagonal().array() += c_.gyr_gain.w;
  // Coefficient-based products (lazyProduct): at these sizes Eigen would otherwise take its
  // blocked GEMM path, whose packing cost three quarters of this update.
  const Eigen::Matrix<double, 9, 2> ph = st_.gyr_gain.p.lazyProduct(reg.transpose());
  s += reg * ph;
  const Eigen::Matrix<double, 9, 2> k = ph * s.inverse();
  const double clip = kGyrGainClip;
  st_.gyr_gain.g = (st_.gyr_gain.g + k * residual).cwiseMax(-clip).cwiseMin(clip);
  st_.gyr_gain.p -= k.lazyProduct(ph.transpose());
}

FilterOutput AttitudeFilter::output() const {
  const bool have_mag = st_.mag_timing.have;
  const bool rejection = p_.mag_dist.rejection;
  FilterOutput o;
  o.q_earth_sensor_6d = st_.inclination.q_acc * st_.strapdown.q_gyr;
  if (have_mag) {  // q_delta turns about z only: its product without the zero terms
    const Eigen::Quaterniond& d = st_.heading.q_delta;
    const Eigen::Quaterniond& q = o.q_earth_sensor_6d;
    o.q_earth_sensor =
        Eigen::Quaterniond(d.w() * q.w() - d.z() * q.z(), d.w() * q.x() - d.z() * q.y(),
                           d.w() * q.y() + d.z() * q.x(), d.w() * q.z() + d.z() * q.w());
  } else {
    o.q_earth_sensor = o.q_earth_sensor_6d;
  }
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
  o.mag_6d_uT = st_.heading.last_m_e;
  return o;
}

}  // namespace mocap
