// Shared by the accuracy regression tests: records a run's headline figures as test properties.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "mocap/sim/accuracy.hpp"

namespace mocap::sim {

inline void record(const AccuracyResult& r) {
  testing::Test::RecordProperty(r.motion + "_" + r.disturbance + "_hinge_deg",
                                std::to_string(r.hinge_max_rmse_deg));
  testing::Test::RecordProperty(r.motion + "_" + r.disturbance + "_three_dof_deg",
                                std::to_string(r.three_dof_max_rmse_deg));
}

}  // namespace mocap::sim
