// Test helper for the glTF tests: a few random solved poses written by GltfWriter.
#pragma once

#include <string>
#include <vector>

#include "mocap/skeleton/gltf.hpp"
#include "mocap/skeleton/skeleton.hpp"
#include "skeleton_test_util.hpp"

namespace mocap::test {

/// A few random solved poses written to `path` at 30 Hz.
inline std::vector<PoseFrame> write_gltf_take(const std::string& path, const BodyModel& model,
                                              int count) {
  std::mt19937 rng(31);
  Skeleton sk(model, default_joint_limits(), RigMapping::full());
  std::vector<PoseFrame> frames;
  GltfWriter w(path, model, {.frame_time_s = 1.0 / 30});
  for (int k = 0; k < count; ++k) {
    const auto pose = random_pose(rng, 70);
    for (int s = 0; s < kSegmentCount; ++s)
      sk.set_sensor_orientation(s, pose[s], k * 33'000'000LL);
    PoseFrame f;
    reset_pose(f);
    sk.solve(f);
    w.write_frame(f);
    frames.push_back(f);
  }
  w.close();
  return frames;
}

}  // namespace mocap::test
