// AttitudeFilter's upset recovery (UpsetParams): after a clipped gyro sample the strapdown may
// have lost rotation. A fresh orientation from acc (and the field) low-passed fast in the
// almost-inertial frame is compared with the filter's; a steady disagreement is corrected at
// once, a steady agreement ends the check.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "mocap/core/units.hpp"
#include "mocap/filter/attitude_filter.hpp"
#include "mocap/filter/filter_constants.hpp"

namespace mocap {

void AttitudeFilter::note_clipped_gyr() {
  UpsetState& u = st_.upset;
  if (!u.checking) {  // the first of this upset: the bias filter as it was before
    u.bias_before_rad_s = st_.bias.rad_s;
    u.bias_p_before = st_.bias.p;
    u.bias_p_init_before = st_.bias.p_init;
  }
  u.checking = true;
  u.since_s = 0;
  u.hold_t_s = 0;
  u.acc_lp.reset();
  u.mag_lp.reset();
  u.mag_t_s = 0;
}

void AttitudeFilter::upset_mag(const Eigen::Vector3d& mag) {
  UpsetState& u = st_.upset;
  if (!u.checking) return;
  const Eigen::Vector3d m_i = st_.strapdown.q_gyr * mag;
  u.mag_lp.step(m_i.data(), c_.upset_mag_lp, kUpsetTau_s, c_.ts.mag_s);
  u.mag_t_s += c_.ts.mag_s;
}

void AttitudeFilter::check_upset(const Eigen::Vector3d& acc) {
  UpsetState& u = st_.upset;
  if (!u.checking) return;
  const double ts = c_.ts.acc_s;
  u.since_s += ts;
  if (u.since_s > kUpsetWindow_s) {
    u.checking = false;
    return;
  }
  const Eigen::Vector3d acc_i = st_.strapdown.q_gyr * acc;
  const auto& f = u.acc_lp.step(acc_i.data(), c_.upset_acc_lp, kUpsetTau_s, ts);
  const Eigen::Vector3d fast_i(f[0], f[1], f[2]);
  const double n = fast_i.norm();
  // Settled (2 tau) and about g; else no verdict.
  if (u.since_s < 2 * kUpsetTau_s ||
      std::abs(n - kStandardGravity_m_s2) > kUpsetNormTol * kStandardGravity_m_s2) {
    u.hold_t_s = 0;
    return;
  }
  // The fresh inclination: q_acc turned by the shortest rotation taking the fast acc onto +z.
  const Eigen::Vector3d up_e = st_.inclination.q_acc * (fast_i / n);
  const Eigen::Quaterniond q_acc_fresh =
      (Eigen::Quaterniond::FromTwoVectors(up_e, Eigen::Vector3d::UnitZ()) * st_.inclination.q_acc)
          .normalized();
  const double incl_rad = std::acos(std::clamp(up_e.z(), -1.0, 1.0));
  // The fresh heading: the fast field's in that frame, if it passes the disturbance tests
  // against the reference (its dip seen through the fresh inclination).
  const MagDisturbanceState& d = st_.mag_dist;
  bool field_ok = false;
  double delta_fresh = st_.heading.delta_rad, head_rad = 0;
  if (d.have_ref && u.mag_t_s >= 2 * kUpsetTau_s) {
    const auto& m = u.mag_lp.out;
    const Eigen::Vector3d m_e = q_acc_fresh * Eigen::Vector3d(m[0], m[1], m[2]);
    const double mn = m_e.norm();
    if (mn > 0) {
      const double dip = -std::asin(std::clamp(m_e.z() / mn, -1.0, 1.0));
      field_ok = field_deviation2(mn, dip, d.ref_norm, d.ref_dip) < 1.0;
      delta_fresh = std::atan2(m_e.x(), m_e.y());
      head_rad =
          std::abs(std::remainder(delta_fresh - st_.heading.delta_rad, 2 * std::numbers::pi));
    }
  }
  // Verdicts: the inclination lost (over kUpsetAngle_deg); with the inclination confirmed (within
  // kUpsetConfirm_deg), the heading lost, or both confirmed; else none. The heading is judged only
  // in a confirmed inclination: seen through a wrong one, the field's heading is wrong too.
  const double angle = kUpsetAngle_deg * kRadPerDeg, confirm = kUpsetConfirm_deg * kRadPerDeg;
  const bool incl_lost = incl_rad > angle, incl_ok = incl_rad < confirm;
  const bool head_lost = incl_ok && field_ok && head_rad > angle;
  const bool disagree = incl_lost || head_lost;
  const bool agree = incl_ok && (!d.have_ref || (field_ok && head_rad < confirm));
  if (!disagree && !agree) {
    u.hold_t_s = 0;
    return;
  }
  // A lost rotation shows as a fixed fresh orientation in the almost-inertial frame; the
  // specific force of a swing (a pendulum's along its rope) or a push turns there.
  const Eigen::Quaterniond q_fresh =
      Eigen::Quaterniond(Eigen::AngleAxisd(delta_fresh, Eigen::Vector3d::UnitZ())) * q_acc_fresh;
  if (disagree != u.disagree || u.hold_t_s == 0 ||
      (disagree && q_fresh.angularDistance(u.q_hold) > kUpsetSteady_deg * kRadPerDeg)) {
    u.disagree = disagree;
    u.q_hold = q_fresh;
    u.hold_t_s = 0;
  }
  u.hold_t_s += ts;
  if (u.hold_t_s < kUpsetHold_s) return;
  u.hold_t_s = 0;
  if (incl_lost) return recover_upset(q_acc_fresh, delta_fresh, false);  // then the heading
  if (head_lost) recover_upset(q_acc_fresh, delta_fresh, true);
  u.checking = false;
}

// The lost rotation: the inclination (and its slow path's state) and, with a good field, the
// heading set to the fresh ones; the bias filter forgets what the upset taught it, and the
// field's rejection (its dip was seen through the wrong inclination) is forgiven.
void AttitudeFilter::recover_upset(const Eigen::Quaterniond& q_acc, double delta_rad,
                                   bool with_heading) {
  UpsetState& u = st_.upset;
  ++cnt_.upset_recoveries;
  InclinationState& in = st_.inclination;
  const Eigen::Vector3d up_i = q_acc.conjugate() * Eigen::Vector3d::UnitZ();
  const auto& lp = in.acc_lp.out;
  const Eigen::Vector3d steady = up_i * Eigen::Vector3d(lp[0], lp[1], lp[2]).norm();
  in.q_acc = q_acc;
  in.acc_lp.set_steady(steady.data(), c_.acc_lp);
  if (with_heading) {
    HeadingState& h = st_.heading;
    h.delta_rad = delta_rad;
    h.q_delta = Eigen::Quaterniond(Eigen::AngleAxisd(delta_rad, Eigen::Vector3d::UnitZ()));
  }
  BiasState& b = st_.bias;
  b.rad_s = u.bias_before_rad_s;
  b.p = u.bias_p_before;
  b.p_init = u.bias_p_init_before;
  b.n = 0;
  b.corr_sum.setZero();
  b.motion_r_lp.reset();
  b.motion_bias_lp.reset();
  MagDisturbanceState& d = st_.mag_dist;
  d.reject_t_s = 0;
  d.cand_t_s = 0;
  d.cand_age_s = 0;
}

}  // namespace mocap
