// glTF 2.0 binary (.glb) writer: our 16 segments as a node hierarchy named like the BVH bones
// (Hips, Spine, ..., RightFoot), bound as the joints of one skin (inverse bind matrices of the
// N-pose rest), and one animation: every node's rotation and the root's translation, linear, at
// a fixed frame time. glTF axes: y up, z forward (the character faces +z), x to the character's
// left, metres, quaternions x, y, z, w (the BVH axes, docs/conventions.md). The rest pose is our
// N-pose, so a node's animated rotation is PoseFrame::q_parent_segment (the root's
// q_earth_segment) in these axes. Frames are kept in memory and the file is written on close.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "mocap/skeleton/body_model.hpp"
#include "mocap/skeleton/pose_frame.hpp"

namespace mocap {

struct GltfWriterOptions {
  double frame_time_s = 1.0 / 60.0;
  std::string animation_name = "mocap";
};

class GltfWriter {
 public:
  /// Checks the options and that `path` can be created (throws std::runtime_error otherwise).
  GltfWriter(const std::string& path, const BodyModel& model, GltfWriterOptions options = {});
  ~GltfWriter();
  GltfWriter(const GltfWriter&) = delete;
  GltfWriter& operator=(const GltfWriter&) = delete;

  /// Appends one frame (root position, q_earth_segment[pelvis], q_parent_segment of the rest).
  void write_frame(const PoseFrame& frame);
  /// Writes the file (also done by the destructor, which swallows errors). Throws on I/O errors.
  void close();
  int frames() const { return frames_; }

 private:
  std::string path_;
  BodyModel model_;
  GltfWriterOptions opt_;
  int frames_ = 0;
  bool closed_ = false;
  std::vector<float> rotations_[kSegmentCount];  // x, y, z, w per frame
  std::vector<float> root_translation_;          // x, y, z per frame
};

/// The .glb bytes of a take (what GltfWriter writes): JSON chunk, then the binary buffer.
std::vector<uint8_t> gltf_binary(const BodyModel& model, const GltfWriterOptions& options,
                                 int frames, const std::vector<float> (&rotations)[kSegmentCount],
                                 const std::vector<float>& root_translation);

}  // namespace mocap
