// Plain forward kinematics into a PoseFrame: from each segment's earth orientation and the root
// position, the joint positions down the parent chain and the joint rotations. Used where the
// orientations are already known (BVH playback, the viewer's procedural poses); the live solver
// (Skeleton) adds calibration, limits and root motion around the same chain walk.
#pragma once

#include <Eigen/Geometry>
#include <array>

#include "mocap/skeleton/body_model.hpp"
#include "mocap/skeleton/pose_frame.hpp"

namespace mocap {

/// Fills out.q_earth_segment, q_parent_segment and p_earth_segment_m (root at p_root_m);
/// leaves every other field alone.
void pose_from_earth_orientations(const BodyDimensions& dims,
                                  const std::array<Eigen::Quaterniond, kSegmentCount>& q_earth,
                                  const Eigen::Vector3d& p_root_m, PoseFrame& out);

}  // namespace mocap
