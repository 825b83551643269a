// Table of FilterParams members by name, for overrides and reports.
#include "mocap/filter/filter_param_names.hpp"

#include <charconv>
#include <cstdio>
#include <variant>

namespace mocap {
namespace {

using Entry = FilterParamEntry;

#define D(n)             \
  Entry {                \
#n, &FilterParams::n \
  }
const Entry kEntries[] = {D(tau_acc_s),
                          D(tau_mag_s),
                          D(heading_sigma_deg),
                          D(mag_trust_weight),
                          D(rest_bias_est),
                          D(motion_bias_est),
                          D(bias_sigma_init_deg_s),
                          D(bias_forgetting_time_s),
                          D(bias_clip_deg_s),
                          D(bias_sigma_motion_deg_s),
                          D(bias_vertical_forgetting),
                          D(bias_sigma_rest_deg_s),
                          D(gyr_gain_sigma_init),
                          D(gyr_gain_forgetting_time_s),
                          D(gyr_gain_clip),
                          D(rest_min_t_s),
                          D(rest_filter_tau_s),
                          D(rest_th_gyr_deg_s),
                          D(rest_th_acc_m_s2),
                          D(mag_dist_rejection),
                          D(mag_current_tau_s),
                          D(mag_ref_tau_s),
                          D(mag_norm_th),
                          D(mag_dip_th_deg),
                          D(mag_new_time_s),
                          D(mag_new_first_time_s),
                          D(mag_new_min_gyr_deg_s),
                          D(mag_min_undisturbed_time_s),
                          D(mag_max_rejection_time_s),
                          D(mag_rejection_factor),
                          D(hard_iron_tau_s),
                          D(hard_iron_sigma0),
                          D(hard_iron_field_rw_deg),
                          D(hard_iron_noise),
                          D(hard_iron_gate),
                          D(hard_iron_min_offset),
                          D(hard_iron_min_sigmas),
                          D(hard_iron_nis_tau_s),
                          D(hard_iron_nis_max),
                          D(hard_iron_step_s),
                          D(hard_iron_select_tau_s),
                          D(hard_iron_select_margin),
                          D(hard_iron_consistent_nis),
                          D(hard_iron_consistent_s),
                          D(hard_iron_consistent_min_sigmas),
                          D(mag_latency_tau_s),
                          D(mag_latency_hp_tau_s),
                          D(mag_latency_min_rate_deg_s),
                          D(mag_latency_max_s),
                          D(max_gap_s),
                          D(max_gyr_rad_s),
                          D(max_acc_m_s2),
                          D(max_mag_uT)};
#undef D

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
    if (auto* m = std::get_if<bool FilterParams::*>(&e.member)) {
      if (val == "1" || val == "true")
        p.*(*m) = true;
      else if (val == "0" || val == "false")
        p.*(*m) = false;
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
    p.*std::get<double FilterParams::*>(e.member) = v;
    return true;
  }
  error = "unknown filter parameter '" + std::string(name) + "'";
  return false;
}

std::string describe_filter_params(const FilterParams& p) {
  std::string out;
  char buf[128];
  for (const auto& e : kEntries) {
    if (auto* m = std::get_if<bool FilterParams::*>(&e.member))
      std::snprintf(buf, sizeof buf, "%s=%s\n", e.name, p.*(*m) ? "true" : "false");
    else
      std::snprintf(buf, sizeof buf, "%s=%g\n", e.name,
                    p.*std::get<double FilterParams::*>(e.member));
    out += buf;
  }
  return out;
}

}  // namespace mocap
