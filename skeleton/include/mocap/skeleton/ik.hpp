// Two-bone analytic inverse kinematics for arms and legs (law of cosines; the thesis's two-link
// solution generalised to 3-D with a bend-direction hint), and the segment orientations that
// realise it with a pure hinge rotation at the middle joint.
#pragma once

#include <Eigen/Geometry>
#include <array>

#include "mocap/core/segments.hpp"
#include "mocap/skeleton/body_model.hpp"

namespace mocap {

struct TwoBoneIk {
  Eigen::Vector3d p_mid_m = Eigen::Vector3d::Zero();  ///< middle joint (knee / elbow)
  Eigen::Vector3d p_end_m = Eigen::Vector3d::Zero();  ///< end joint (ankle / wrist)
  bool reached = false;  ///< false: target out of reach, the chain points at it
};

/// root: upper joint position; l_upper, l_lower: bone lengths; bend_hint: the direction the middle
/// joint should bend towards (e.g. forward for a knee, backward for an elbow).
TwoBoneIk solve_two_bone_ik(const Eigen::Vector3d& root, double l_upper, double l_lower,
                            const Eigen::Vector3d& target, const Eigen::Vector3d& bend_hint);

/// IK for a limb of the body model: sets q_earth_segment of `upper` (thigh_l/r or upper_arm_l/r)
/// and its child so that the child's child joint (ankle / wrist) reaches target. p_upper_m: the
/// upper segment's joint position. The middle joint becomes a pure flexion about the segment y
/// axis (positive for knees, negative for elbows, as the joint limits expect). The twist of the
/// upper segment is chosen so that its hinge axis is perpendicular to the bend plane.
TwoBoneIk solve_limb_ik(const BodyModel& model, Segment upper, const Eigen::Vector3d& p_upper_m,
                        const Eigen::Vector3d& target, const Eigen::Vector3d& bend_hint,
                        std::array<Eigen::Quaterniond, kSegmentCount>& q_earth_segment);

}  // namespace mocap
