// The calibration procedure as a motion of its own (sim-internal): the N-pose stand, the
// calibration moves and a closing stand, facing +x, without root translation. A BVH motion plays
// it before its clip ("calibrate+FILE.bvh").
#pragma once

#include <memory>

#include "mocap/sim/motion.hpp"

namespace mocap::sim {

/// 3 s N-pose stand (calibration window [0, 3]), then calibration_moves_s() of knee bends with
/// elbow curls ending in a 1 s stand.
std::unique_ptr<Motion> make_calibration_procedure();

}  // namespace mocap::sim
