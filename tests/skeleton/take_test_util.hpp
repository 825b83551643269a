// Test helper for the exporter tests (BVH, glTF): random solved poses fed to a pose writer.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "mocap/skeleton/gltf.hpp"
#include "mocap/skeleton/skeleton.hpp"
#include "skeleton_test_util.hpp"

namespace mocap::test {

/// `count` random poses (joints up to max_deg, seeded with `seed`), solved by a full-rig
/// Skeleton dt_ns apart and written to `w` (a BvhWriter, GltfWriter, ...); returns the frames.
template <class Writer>
std::vector<PoseFrame> write_random_take(Writer& w, const BodyModel& model, int count,
                                         unsigned seed, double max_deg, int64_t dt_ns) {
  std::mt19937 rng(seed);
  Skeleton sk(model, default_joint_limits(), RigMapping::full());
  std::vector<PoseFrame> frames;
  for (int k = 0; k < count; ++k) {
    const auto pose = random_pose(rng, max_deg);
    for (int s = 0; s < kSegmentCount; ++s)
      sk.set_sensor_orientation(s, pose[s], k * dt_ns);
    PoseFrame f;
    reset_pose(f);
    sk.solve(f);
    w.write_frame(f);
    frames.push_back(f);
  }
  return frames;
}

/// The Blender tests' take: a few random solved poses (seed 31, up to 70 deg) 33 ms apart.
template <class Writer>
std::vector<PoseFrame> write_blender_take(Writer& w, const BodyModel& model, int count) {
  return write_random_take(w, model, count, 31, 70, 33'000'000);
}

/// A few random solved poses written to `path` as glTF at 30 Hz.
inline std::vector<PoseFrame> write_gltf_take(const std::string& path, const BodyModel& model,
                                              int count) {
  GltfWriter w(path, model, {.frame_time_s = 1.0 / 30});
  auto frames = write_blender_take(w, model, count);
  w.close();
  return frames;
}

}  // namespace mocap::test
