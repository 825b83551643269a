// Plausibility test for one measurement vector, shared by every filter: rejects NaN/Inf, zero
// and absurd magnitudes and counts each kind, so bad input never reaches a filter state.
#pragma once

#include <Eigen/Core>
#include <cmath>

namespace mocap {

/// True when v is finite and min_norm < |v| <= max_norm. Otherwise increments the matching
/// counter of `c` (any struct with nonfinite, zero_vector and out_of_range members).
template <class Counters>
bool check_vector(const Eigen::Vector3d& v, double min_norm, double max_norm, Counters& c) {
  if (!std::isfinite(v.x()) || !std::isfinite(v.y()) || !std::isfinite(v.z())) {
    ++c.nonfinite;
    return false;
  }
  const double n2 = v.squaredNorm();
  if (min_norm > 0 && n2 <= min_norm * min_norm) {
    ++c.zero_vector;
    return false;
  }
  if (n2 > max_norm * max_norm) {
    ++c.out_of_range;
    return false;
  }
  return true;
}

}  // namespace mocap
