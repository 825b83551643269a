// The simulator's ground-truth body state and its own forward kinematics. Written independently of
// the skeleton module's solver (which is the system under test): joint rotations plus the pelvis
// pose give every segment's earth orientation and joint position using BodyDimensions offsets.
// Frames as in docs/conventions.md: earth ENU z up; every segment frame equals the body frame in
// the N-pose (all joint rotations identity).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>

#include "mocap/core/segments.hpp"
#include "mocap/skeleton/body_model.hpp"
#include "mocap/skeleton/pose_frame.hpp"

namespace mocap::sim {

/// Joint-space body state at one instant.
struct BodyPose {
  Eigen::Quaterniond q_earth_pelvis = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p_earth_pelvis_m = Eigen::Vector3d::Zero();  ///< pelvis origin (hip midpoint)
  /// Joint rotation of each segment relative to its parent (index 0, the pelvis, is unused).
  std::array<Eigen::Quaterniond, kSegmentCount> q_parent_segment;
  BodyPose() { q_parent_segment.fill(Eigen::Quaterniond::Identity()); }
};

/// Earth-frame state of every segment at one instant: what the tracker should reproduce.
struct TruthFrame {
  double t_s = 0;  ///< performer time, seconds since the performer started
  std::array<Eigen::Quaterniond, kSegmentCount> q_earth_segment;
  std::array<Eigen::Vector3d, kSegmentCount> p_earth_segment_m;    ///< joint (origin) positions
  std::array<Eigen::Quaterniond, kSegmentCount> q_parent_segment;  ///< joint rotations
};

/// Forward kinematics of the ground truth: fills q_earth_segment, p_earth_segment_m and
/// q_parent_segment of `out` (t_s untouched).
void truth_forward_kinematics(const BodyDimensions& dims, const BodyPose& pose, TruthFrame& out);

/// The truth as a PoseFrame (segment orientations, joint positions and rotations; every other
/// field default), e.g. for a BVH file of the ground truth.
PoseFrame to_pose_frame(const TruthFrame& truth);

}  // namespace mocap::sim
