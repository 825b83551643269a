// Shared by the accuracy regression tests: options of a cell after the calibration moves, and
// a run's headline figures recorded as test properties.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <utility>

#include "mocap/sim/accuracy.hpp"

namespace mocap::sim {

/// Options of a cell calibrated with the calibration procedure (N-pose + calibration moves).
inline AccuracyOptions after_moves(std::string motion, uint64_t seed = 1) {
  AccuracyOptions o;
  o.motion = std::move(motion);
  o.seed = seed;
  o.calibration_moves = true;
  return o;
}

inline void record(const AccuracyResult& r) {
  testing::Test::RecordProperty(r.motion + "_" + r.disturbance + "_hinge_deg",
                                std::to_string(r.hinge_max_rmse_deg));
  testing::Test::RecordProperty(r.motion + "_" + r.disturbance + "_three_dof_deg",
                                std::to_string(r.three_dof_max_rmse_deg));
}

}  // namespace mocap::sim
