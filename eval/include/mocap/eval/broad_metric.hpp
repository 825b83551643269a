// The BROAD benchmark's orientation error metric: e = q_est * q_ref^-1 in the earth frame,
// total / heading / inclination angles, RMS over movement samples with a finite reference.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <string>
#include <vector>

#include "mocap/eval/broad_csv.hpp"

namespace mocap {

/// RMS errors of one trial in degrees; n = number of samples scored.
struct AttitudeErrors {
  double total_deg = 0, heading_deg = 0, inclination_deg = 0;
  size_t n = 0;
};

/// Per-sample error angles (radians) between an estimate and a reference, both sensor -> ENU.
void attitude_error_angles(const Eigen::Quaterniond& q_est, const Eigen::Quaterniond& q_ref,
                           double& total_rad, double& heading_rad, double& inclination_rad);

/// Scores estimates (one per sample) against the trial's reference over movement samples.
AttitudeErrors score_trial(const BroadTrial& trial, const std::vector<Eigen::Quaterniond>& est);

/// VQF 2.1.1 per-trial figures (9D total, 9D heading, 6D inclination, degrees) from the
/// dataset README, for the trial whose name starts with prefix ("36_").
struct VqfRef {
  const char* prefix;
  double total, heading, incl6;
};
/// The VQF figures for a trial name, or nullptr for a trial the README does not list.
const VqfRef* vqf_reference(const std::string& trial_name);

}  // namespace mocap
