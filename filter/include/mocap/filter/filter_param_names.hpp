// Name-based access to FilterParams ("tau_mag_s=12") for the daemon's [filter] config keys,
// command-line overrides and docs. The names are the user-visible keys (flat, historical: kept
// when the members moved into per-stage structs, so users' config files keep working).
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <variant>

#include "mocap/filter/filter_params.hpp"

namespace mocap {

/// One FilterParams member by name: the filter's parameters as the daemon's configuration
/// ([filter] keys) and the tools' --set options address them.
struct FilterParamEntry {
  using Number = double& (*)(FilterParams&);
  using Flag = bool& (*)(FilterParams&);
  const char* name;    ///< the key, e.g. "bias_clip_deg_s"
  const char* member;  ///< the member it binds, e.g. "bias.clip_deg_s"
  std::variant<Number, Flag> ref;

  bool is_flag() const { return std::holds_alternative<Flag>(ref); }
  double& number(FilterParams& p) const { return std::get<Number>(ref)(p); }
  bool& flag(FilterParams& p) const { return std::get<Flag>(ref)(p); }
  double number(const FilterParams& p) const { return number(const_cast<FilterParams&>(p)); }
  bool flag(const FilterParams& p) const { return flag(const_cast<FilterParams&>(p)); }
};
/// Every tunable FilterParams member, in declaration order.
std::span<const FilterParamEntry> filter_param_table();

/// Applies "name=value". Returns false with a message for an unknown name or bad value.
bool set_filter_param(FilterParams& p, std::string_view assignment, std::string& error);

/// "name=value" lines of every parameter (for reports).
std::string describe_filter_params(const FilterParams& p);

}  // namespace mocap
