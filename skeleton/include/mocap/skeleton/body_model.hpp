// Body dimensions of the 16-segment thesis model for a person of a given height: joint offsets
// (each segment's joint position in its parent's frame) and segment end points, from
// anthropometric ratios (Winter, "Biomechanics and Motor Control of Human Movement", segment
// lengths as fractions of height). Every value can be overridden from the config.
//
// Frames: the body frame and, in the reference pose (N-pose: standing, arms hanging, facing
// forward), every segment frame are x forward, y to the person's left, z up (right-handed).
#pragma once

#include <Eigen/Core>
#include <array>

#include "mocap/core/segments.hpp"

namespace mocap {

struct BodyDimensions {
  double height_m = 1.75;
  /// Position of each segment's joint in its parent segment's frame, metres (reference pose).
  /// For the pelvis: the pelvis origin (midpoint of the hip joints) above the floor.
  std::array<Eigen::Vector3d, kSegmentCount> joint_offset_m{};
  /// Distal end of each segment (tip of the bone) in its own frame, metres.
  std::array<Eigen::Vector3d, kSegmentCount> end_offset_m{};
};

/// Dimensions scaled from body height by anthropometric ratios.
BodyDimensions body_dimensions_from_height(double height_m);

/// Earth-frame joint positions in the reference pose, pelvis origin at (0, 0, pelvis height),
/// facing +x. Used by tests, the simulator and the viewer's rest pose.
std::array<Eigen::Vector3d, kSegmentCount> reference_joint_positions(const BodyDimensions& dims);

}  // namespace mocap
