// Joint constraints: swing-twist limits for 3-DOF joints (an elliptical swing cone with
// separate half-angles per direction, plus a twist range) and hinge limits for knees and elbows
// (flexion range about the hinge axis, a small off-axis tolerance, a twist range). Defaults come
// from the thesis table (Usta 1999, Tables 1-5) and standard ranges of motion; right-side limits
// mirror the left. Checking is allocation-free and costs two atan2 and a few multiplies.
//
// Angles: q_parent_segment = swing * twist, twist about the segment's bone axis (a coordinate
// axis of the segment frame), the swing a rotation vector perpendicular to it whose components
// about the two other coordinate axes ("a" and "b") are limited. Degrees everywhere.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <string>
#include <string_view>

#include "mocap/core/segments.hpp"

namespace mocap {

struct JointLimit {
  bool limited = false;  ///< false: free joint (the root), never violated
  bool hinge = false;    ///< true: swing a/b checked as a box (hinge), else as an ellipse
  int twist_axis = 2;    ///< segment-frame axis of the bone (0 x, 1 y, 2 z)
  int axis_a = 0;        ///< first swing axis
  int axis_b = 1;        ///< second swing axis (the hinge axis for hinges)
  double a_min_deg = 0, a_max_deg = 0;
  double b_min_deg = 0, b_max_deg = 0;
  double twist_min_deg = 0, twist_max_deg = 0;
  bool operator==(const JointLimit&) const = default;
};

struct JointLimits {
  std::array<JointLimit, kSegmentCount> joint{};
};

/// Anatomical defaults (see docs/skeleton.md for the table).
JointLimits default_joint_limits();

/// Mirrors a left-side limit to the right side (reflection y -> -y: angles about x and z change
/// sign, angles about y keep it).
JointLimit mirror_limit(const JointLimit& left);

/// Throws std::invalid_argument if a range is inverted, excludes 0 (the N-pose), or axes repeat.
void validate(const JointLimits& limits);

/// Parses limits from TOML, starting from the defaults:
///   [joint.knee_l]          # joint names (kJointNames) or segment names
///   b_deg = [-5, 150]       # also a_deg, twist_deg; hinge = true/false
/// Throws std::runtime_error naming source:line:column and the problem.
JointLimits parse_joint_limits(std::string_view toml_text, std::string_view source = "limits");
/// Reads and parses a joint-limits file (throws std::runtime_error on I/O or parse errors).
JointLimits load_joint_limits(const std::string& path);

struct JointCheck {
  double violation_deg = 0;  ///< angle between the joint rotation and its clamped version
  double a_deg = 0, b_deg = 0, twist_deg = 0;  ///< decomposed joint angles
  bool violated = false;
};

/// Decomposes q_parent_segment, checks it and, if `clamped` is given, writes the nearest allowed
/// rotation (radial projection onto the swing ellipse, twist clamped to its range).
JointCheck check_joint(const JointLimit& limit, const Eigen::Quaterniond& q_parent_segment,
                       Eigen::Quaterniond* clamped = nullptr);

}  // namespace mocap
