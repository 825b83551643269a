// BVH (Biovision Hierarchy) writer and reader.
//
// Writer: our 16 segments as standard bones (Hips, Spine, Neck, Head, LeftArm, LeftForeArm,
// LeftHand, RightArm, ..., LeftUpLeg, LeftLeg, LeftFoot, ...), one token group per line (Blender's
// line-oriented parser), root OFFSET 0 0 0 with Xposition Yposition Zposition, every joint three
// rotation channels Zrotation Xrotation Yrotation (R = Rz Rx Ry), centimetres, a fixed frame
// time. BVH axes: x = the character's left, y up, z forward (docs/conventions.md). The rest pose
// is our N-pose, so local rotations are exactly PoseFrame::q_parent_segment. Frames stream to the
// file; the frame count is patched on close.
//
// Reader: any BVH (any channel order, extra joints such as collars or several spine joints, T- or
// N-pose rest). parse_bvh gives the raw clip; BvhMotion maps it onto our segments by bone name
// (common aliases accepted), re-expresses rotations in our N-pose segment frames and derives body
// dimensions from the file's offsets, so our forward kinematics reproduces the file's joints.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "mocap/skeleton/body_model.hpp"
#include "mocap/skeleton/pose_frame.hpp"

namespace mocap {

/// Standard BVH bone name of each segment.
inline constexpr std::array<std::string_view, kSegmentCount> kBvhBoneNames = {
    "Hips",     "Spine",      "Neck",         "Head",      "LeftArm",   "LeftForeArm",
    "LeftHand", "RightArm",   "RightForeArm", "RightHand", "LeftUpLeg", "LeftLeg",
    "LeftFoot", "RightUpLeg", "RightLeg",     "RightFoot"};

/// Rotation taking our body/earth axes (x fwd, y left, z up) to BVH axes (x left, y up, z fwd).
Eigen::Quaterniond q_bvh_body();

/// Euler angles (degrees) for R = Rz(z) Rx(x) Ry(y) and back.
Eigen::Vector3d zxy_degrees_from_rotation(const Eigen::Quaterniond& q);  ///< returns (z, x, y)
Eigen::Quaterniond rotation_from_zxy_degrees(double z_deg, double x_deg, double y_deg);

struct BvhWriterOptions {
  double frame_time_s = 1.0 / 60.0;
  double units_per_m = 100.0;  ///< centimetres
};

class BvhWriter {
 public:
  /// Opens `path` and writes the hierarchy. Throws std::runtime_error on I/O errors.
  BvhWriter(const std::string& path, const BodyModel& model, BvhWriterOptions options = {});
  ~BvhWriter();
  BvhWriter(const BvhWriter&) = delete;
  BvhWriter& operator=(const BvhWriter&) = delete;

  /// Appends one frame (root position, q_earth_segment[pelvis], q_parent_segment of the rest).
  /// No allocation. Throws std::runtime_error if the write fails.
  void write_frame(const PoseFrame& frame);
  /// Patches the frame count and closes the file (also done by the destructor).
  void close();
  int frames() const { return frames_; }

 private:
  std::FILE* f_ = nullptr;
  long frames_pos_ = 0;
  int frames_ = 0;
  BvhWriterOptions opt_;
  std::string path_;
  /// Per segment, the rotation written last (its PoseFrame floats, bit for bit) and its three
  /// angles' text (" z x y"): a rotation that did not change since the previous frame (about
  /// one in seven in a replay: frames at 120 Hz, samples at 100 Hz) is copied, not recomputed.
  struct LastRotation {
    std::array<float, 4> wxyz{};
    char text[3 * 24] = {};
    int length = 0;  ///< 0: none yet
  };
  std::array<LastRotation, kSegmentCount> last_{};
};

/// Writes the HIERARCHY section for our skeleton (used by BvhWriter; handy for tests).
std::string bvh_hierarchy(const BodyModel& model, double units_per_m = 100.0);

enum class BvhChannel : uint8_t { xpos, ypos, zpos, xrot, yrot, zrot };

struct BvhJoint {
  std::string name;
  int parent = -1;  ///< index into BvhClip::joints, -1 for the root
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  ///< file units, parent frame
  std::vector<BvhChannel> channels;
  int first_channel = 0;  ///< index of its first value in a frame
  bool has_end_site = false;
  Eigen::Vector3d end_site = Eigen::Vector3d::Zero();
};

struct BvhClip {
  std::vector<BvhJoint> joints;  ///< depth-first, parents first
  int channel_count = 0;
  int frame_count = 0;
  double frame_time_s = 0;
  std::vector<double> values;  ///< frame_count * channel_count

  const double* frame(int k) const {
    return values.data() + static_cast<size_t>(k) * channel_count;
  }
  int find(std::string_view name) const;  ///< joint index (case-insensitive), -1 if absent
  /// Global rotation (BVH axes) and position (file units) of every joint in frame k.
  void global_pose(int k, std::vector<Eigen::Quaterniond>& q,
                   std::vector<Eigen::Vector3d>& p) const;
};

/// Parses BVH text. Throws std::runtime_error "source:line: problem" on malformed input.
BvhClip parse_bvh(std::string_view text, std::string_view source = "bvh");
BvhClip load_bvh(const std::string& path);

/// A BVH clip mapped onto our segments.
class BvhMotion {
 public:
  /// Throws std::runtime_error if the clip has no recognisable hips.
  explicit BvhMotion(BvhClip clip, double m_per_unit = 0.01);

  int frames() const { return clip_.frame_count; }
  double frame_time_s() const { return clip_.frame_time_s; }
  /// BVH joint index driving each segment, -1 if the file lacks it (the segment then follows
  /// its parent).
  const std::array<int, kSegmentCount>& joint_for_segment() const { return joint_; }
  /// Body dimensions from the file's offsets (segments it lacks keep the anthropometric value
  /// for the file's height).
  const BodyDimensions& dimensions() const { return dims_; }
  /// Earth-frame segment orientations (our axes, N-pose = identity) and root position (m).
  void frame(int k, std::array<Eigen::Quaterniond, kSegmentCount>& q_earth_segment,
             Eigen::Vector3d& p_root_m) const;
  /// Fills a PoseFrame by forward kinematics with dimensions() (orientations, joint rotations,
  /// positions); frame number and t_ns from k and the frame time.
  void to_pose_frame(int k, PoseFrame& out) const;
  const BvhClip& clip() const { return clip_; }

 private:
  BvhClip clip_;
  double m_per_unit_;
  std::array<int, kSegmentCount> joint_{};
  std::array<Eigen::Quaterniond, kSegmentCount> q_fix_;  ///< BVH rest frame -> our segment frame
  BodyDimensions dims_;
  mutable std::vector<Eigen::Quaterniond> gq_;
  mutable std::vector<Eigen::Vector3d> gp_;
};

}  // namespace mocap
