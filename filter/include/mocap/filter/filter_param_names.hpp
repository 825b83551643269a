// Name-based access to FilterParams ("tau_mag_s=12") for command-line overrides and docs.
#pragma once

#include <string>
#include <string_view>

#include "mocap/filter/attitude_filter.hpp"

namespace mocap {

/// Applies "name=value". Returns false with a message for an unknown name or bad value.
bool set_filter_param(FilterParams& p, std::string_view assignment, std::string& error);

/// "name=value" lines of every parameter (for reports).
std::string describe_filter_params(const FilterParams& p);

}  // namespace mocap
