// Table of FilterParams members by their user-visible names (config keys, --set), for
// overrides and reports: one line per key, naming the per-stage member it binds.
#include "mocap/filter/filter_param_names.hpp"

#include <charconv>
#include <cstdio>
#include <variant>

namespace mocap {
namespace {

using Entry = FilterParamEntry;

/// The member Field of the stage struct Stage of p.
template <auto Stage, auto Field>
auto& bind(FilterParams& p) {
  return (p.*Stage).*Field;
}

// KEY: the user-visible name (config key, --set); STAGE.FIELD: the member it binds.
#define P(KEY, STAGE, FIELD)                                                                      \
  Entry {                                                                                         \
#KEY, #STAGE "." #FIELD, &bind < &FilterParams::STAGE, &decltype(FilterParams::STAGE)::FIELD> \
  }
const Entry kEntries[] = {
    P(tau_acc_s, inclination, tau_acc_s),
    P(tau_mag_s, heading, tau_mag_s),
    P(heading_sigma_deg, heading, sigma_deg),
    P(mag_trust_weight, mag_dist, trust_weight),
    P(rest_bias_est, bias, rest_est),
    P(motion_bias_est, bias, motion_est),
    P(bias_sigma_init_deg_s, bias, sigma_init_deg_s),
    P(bias_forgetting_time_s, bias, forgetting_time_s),
    P(bias_clip_deg_s, bias, clip_deg_s),
    P(bias_sigma_motion_deg_s, bias, sigma_motion_deg_s),
    P(bias_vertical_forgetting, bias, vertical_forgetting),
    P(bias_sigma_rest_deg_s, bias, sigma_rest_deg_s),
    P(gyr_gain_sigma_init, gyr_gain, sigma_init),
    P(gyr_gain_forgetting_time_s, gyr_gain, forgetting_time_s),
    P(gyr_gain_clip, gyr_gain, clip),
    P(rest_min_t_s, rest, min_t_s),
    P(rest_filter_tau_s, rest, filter_tau_s),
    P(rest_th_gyr_deg_s, rest, th_gyr_deg_s),
    P(rest_th_acc_m_s2, rest, th_acc_m_s2),
    P(mag_dist_rejection, mag_dist, rejection),
    P(mag_current_tau_s, mag_dist, current_tau_s),
    P(mag_ref_tau_s, mag_dist, ref_tau_s),
    P(mag_norm_th, mag_dist, norm_th),
    P(mag_dip_th_deg, mag_dist, dip_th_deg),
    P(mag_heading_th_deg, mag_dist, heading_th_deg),
    P(mag_new_time_s, mag_dist, new_time_s),
    P(mag_new_first_time_s, mag_dist, new_first_time_s),
    P(mag_new_min_gyr_deg_s, mag_dist, new_min_gyr_deg_s),
    P(mag_min_undisturbed_time_s, mag_dist, min_undisturbed_time_s),
    P(mag_max_rejection_time_s, mag_dist, max_rejection_time_s),
    P(mag_rejection_factor, mag_dist, rejection_factor),
    P(hard_iron_tau_s, hard_iron, tau_s),
    P(hard_iron_sigma0, hard_iron, sigma0),
    P(hard_iron_field_rw_deg, hard_iron, field_rw_deg),
    P(hard_iron_noise, hard_iron, noise),
    P(hard_iron_gate, hard_iron, gate),
    P(hard_iron_min_offset, hard_iron, min_offset),
    P(hard_iron_min_sigmas, hard_iron, min_sigmas),
    P(hard_iron_nis_tau_s, hard_iron, nis_tau_s),
    P(hard_iron_nis_max, hard_iron, nis_max),
    P(hard_iron_step_s, hard_iron, step_s),
    P(hard_iron_select_tau_s, hard_iron, select_tau_s),
    P(hard_iron_select_margin, hard_iron, select_margin),
    P(hard_iron_consistent_nis, hard_iron, consistent_nis),
    P(hard_iron_consistent_s, hard_iron, consistent_s),
    P(hard_iron_consistent_min_sigmas, hard_iron, consistent_min_sigmas),
    P(mag_latency_tau_s, mag_latency, tau_s),
    P(mag_latency_hp_tau_s, mag_latency, hp_tau_s),
    P(mag_latency_min_rate_deg_s, mag_latency, min_rate_deg_s),
    P(mag_latency_max_s, mag_latency, max_s),
    P(max_gap_s, input, max_gap_s),
    P(max_gyr_rad_s, input, max_gyr_rad_s),
    P(max_acc_m_s2, input, max_acc_m_s2),
    P(max_mag_uT, input, max_mag_uT),
    P(upset_recovery, upset, enabled),
    P(upset_gyr_deg_s, upset, gyr_deg_s),
    P(upset_tau_s, upset, tau_s),
    P(upset_window_s, upset, window_s),
    P(upset_angle_deg, upset, angle_deg),
    P(upset_confirm_deg, upset, confirm_deg),
    P(upset_steady_deg, upset, steady_deg),
    P(upset_hold_s, upset, hold_s),
    P(upset_norm_tol, upset, norm_tol),
};
#undef P

}  // namespace

std::span<const FilterParamEntry> filter_param_table() {
  return kEntries;
}

bool set_filter_param(FilterParams& p, std::string_view a, std::string& error) {
  const size_t eq = a.find('=');
  if (eq == std::string_view::npos) {
    error = "expected name=value";
    return false;
  }
  const std::string_view name = a.substr(0, eq), val = a.substr(eq + 1);
  for (const auto& e : kEntries) {
    if (name != e.name) continue;
    if (e.is_flag()) {
      if (val == "1" || val == "true")
        e.flag(p) = true;
      else if (val == "0" || val == "false")
        e.flag(p) = false;
      else {
        error = "expected true/false for " + std::string(name);
        return false;
      }
      return true;
    }
    double v = 0;
    auto r = std::from_chars(val.data(), val.data() + val.size(), v);
    if (r.ec != std::errc() || r.ptr != val.data() + val.size()) {
      error = "not a number: '" + std::string(val) + "'";
      return false;
    }
    e.number(p) = v;
    return true;
  }
  error = "unknown filter parameter '" + std::string(name) + "'";
  return false;
}

std::string describe_filter_params(const FilterParams& p) {
  std::string out;
  char buf[128];
  for (const auto& e : kEntries) {
    if (e.is_flag())
      std::snprintf(buf, sizeof buf, "%s=%s\n", e.name, e.flag(p) ? "true" : "false");
    else
      std::snprintf(buf, sizeof buf, "%s=%g\n", e.name, e.number(p));
    out += buf;
  }
  return out;
}

}  // namespace mocap
