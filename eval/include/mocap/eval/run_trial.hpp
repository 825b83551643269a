// Runs one of the attitude algorithms over a recorded trial (shared by `mocap filter`,
// `mocap evaluate`, `mocap bench filter` and the tests).
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string_view>
#include <vector>

#include "mocap/core/imu_sample.hpp"
#include "mocap/eval/broad_csv.hpp"
#include "mocap/filter/attitude_filter.hpp"

namespace mocap {

enum class FilterAlgorithm { kDefault, kMadgwick, kMahony };
enum class FilterMode { k9d, k6d };

std::optional<FilterAlgorithm> parse_filter_algorithm(std::string_view name);
std::optional<FilterMode> parse_filter_mode(std::string_view name);
const char* filter_algorithm_name(FilterAlgorithm a);

/// Sample i of a trial as an ImuSample (gyr+acc, plus mag in 9D when the trial has one).
ImuSample trial_sample(const BroadTrial& trial, size_t i, FilterMode mode);

/// Runs the algorithm over every sample; out[i] = q_earth_sensor after sample i.
void run_trial(const BroadTrial& trial, FilterAlgorithm alg, FilterMode mode,
               const FilterParams& params, std::vector<Eigen::Quaterniond>& out);

}  // namespace mocap
