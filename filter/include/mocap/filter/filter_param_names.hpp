// Name-based access to FilterParams ("tau_mag_s=12") for command-line overrides and docs.
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <variant>

#include "mocap/filter/attitude_filter.hpp"

namespace mocap {

/// One FilterParams member by name: the filter's parameters as the daemon's configuration
/// ([filter] keys) and the tools' --param options address them.
struct FilterParamEntry {
  const char* name;
  std::variant<double FilterParams::*, bool FilterParams::*> member;
};
/// Every tunable FilterParams member, in declaration order.
std::span<const FilterParamEntry> filter_param_table();

/// Applies "name=value". Returns false with a message for an unknown name or bad value.
bool set_filter_param(FilterParams& p, std::string_view assignment, std::string& error);

/// "name=value" lines of every parameter (for reports).
std::string describe_filter_params(const FilterParams& p);

}  // namespace mocap
