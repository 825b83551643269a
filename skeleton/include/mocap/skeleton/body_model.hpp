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
#include <optional>
#include <string>
#include <string_view>

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

/// Editable form of the body model (what the config file holds): the height, and optional
/// per-segment overrides of the anthropometric joint and end offsets (metres, segment frames).
struct BodyModelConfig {
  double height_m = 1.75;
  std::array<std::optional<Eigen::Vector3d>, kSegmentCount> joint_offset_m{};
  std::array<std::optional<Eigen::Vector3d>, kSegmentCount> end_offset_m{};
};

/// Parses a body model from TOML text:
///   height_m = 1.80
///   [segment.forearm_l]            # any segment name; both keys optional
///   joint_offset_m = [0, 0, -0.30]
///   end_offset_m = [0, 0, -0.25]
/// Throws std::runtime_error naming source:line:column and the problem (unknown segment or key,
/// wrong type, out-of-range or non-finite value).
BodyModelConfig parse_body_config(std::string_view toml_text, std::string_view source = "body");
/// Reads and parses a body config file (throws std::runtime_error on I/O or parse errors).
BodyModelConfig load_body_config(const std::string& path);

/// Immutable runtime body model, built once from the editable form: parent-index array in
/// depth-first order (parent < child) and the resolved offsets. Cheap to copy.
class BodyModel {
 public:
  explicit BodyModel(const BodyModelConfig& config = {});
  explicit BodyModel(const BodyDimensions& dims);

  const BodyDimensions& dimensions() const { return dims_; }
  double height_m() const { return dims_.height_m; }
  int parent(int segment) const { return parent_[segment]; }
  const std::array<int8_t, kSegmentCount>& parents() const { return parent_; }
  const Eigen::Vector3d& joint_offset_m(int segment) const { return dims_.joint_offset_m[segment]; }
  const Eigen::Vector3d& end_offset_m(int segment) const { return dims_.end_offset_m[segment]; }
  /// Height of the pelvis origin above the floor in the reference pose.
  double pelvis_height_m() const { return dims_.joint_offset_m[0].z(); }
  /// Distance from the child joint to the parent joint (bone length), metres.
  double bone_length_m(int segment) const { return dims_.joint_offset_m[segment].norm(); }

 private:
  BodyDimensions dims_;
  std::array<int8_t, kSegmentCount> parent_ = kSegmentParent;
};

}  // namespace mocap
