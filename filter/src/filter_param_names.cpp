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
    P(bias_forgetting_time_s, bias, forgetting_time_s),
    P(bias_clip_deg_s, bias, clip_deg_s),
    P(bias_sigma_motion_deg_s, bias, sigma_motion_deg_s),
    P(bias_sigma_rest_deg_s, bias, sigma_rest_deg_s),
    P(gyr_gain_sigma_init, gyr_gain, sigma_init),
    P(rest_min_t_s, rest, min_t_s),
    P(rest_th_gyr_deg_s, rest, th_gyr_deg_s),
    P(rest_th_acc_m_s2, rest, th_acc_m_s2),
    P(mag_dist_rejection, mag_dist, rejection),
    P(mag_ref_tau_s, mag_dist, ref_tau_s),
    P(mag_norm_th, mag_dist, norm_th),
    P(mag_dip_th_deg, mag_dist, dip_th_deg),
    P(mag_heading_th_deg, mag_dist, heading_th_deg),
    P(mag_new_time_s, mag_dist, new_time_s),
    P(hard_iron_tau_s, hard_iron, tau_s),
    P(hard_iron_gate, hard_iron, gate),
    P(mag_latency_tau_s, mag_latency, tau_s),
    P(upset_recovery, upset, enabled),
    P(upset_gyr_deg_s, upset, gyr_deg_s),
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
  error = "unknown filter parameter '" + std::string(name) +
          "' (the parameters: docs/configuration.md [filter]; the fixed constants: "
          "filter/include/mocap/filter/filter_constants.hpp)";
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
