// Test helper for the exporters proven against Blender (headless) as a real third-party reader:
// runs one of the tests/skeleton/blender_*_dump.py scripts on our file (through the shared
// runner, tests/common/blender_runner.hpp) and compares the bone rotations and positions Blender
// reconstructs with ours.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "../common/blender_runner.hpp"
#include "mocap/skeleton/bvh.hpp"
#include "skeleton_test_util.hpp"

namespace mocap::test {

/// Runs tests/skeleton/<script> in headless Blender with the space-separated `args`, its output
/// in `log`, then reads the JSON the script wrote to `json_path` into *out.
inline ::testing::AssertionResult run_blender_dump(const std::string& script,
                                                   const std::string& args,
                                                   const std::string& json_path,
                                                   const std::string& log, nlohmann::json* out) {
  std::remove(json_path.c_str());
  std::vector<std::string> argv;
  std::istringstream words(args);
  for (std::string w; words >> w;)
    argv.push_back(w);
  if (run_blender(std::string(MOCAP_SOURCE_DIR) + "/tests/skeleton/" + script, argv, log) != 0)
    return ::testing::AssertionFailure() << "blender failed; see " << log;
  std::ifstream in(json_path);
  if (!in) return ::testing::AssertionFailure() << "no output from blender";
  *out = nlohmann::json::parse(in);
  return ::testing::AssertionSuccess();
}

/// Every bone of every frame Blender reconstructed (`frames_json`, the dump scripts' "frames")
/// against ours: rotation within 0.01 deg, head within 0.2 mm. Blender's world is our file's
/// axes (BVH or glTF, y up) turned +90 deg about x (z up).
inline void expect_blender_bones_match(const nlohmann::json& frames_json,
                                       const std::vector<PoseFrame>& frames) {
  const Eigen::Quaterniond a = axis_rotation(0, M_PI / 2) * q_bvh_body();
  for (size_t k = 0; k < frames.size(); ++k) {
    const auto& fb = frames_json[k];
    for (int s = 0; s < kSegmentCount; ++s) {
      const auto& b = fb.at(std::string(kBvhBoneNames[s]));
      const Eigen::Quaterniond qb(b["q"][0].get<double>(), b["q"][1].get<double>(),
                                  b["q"][2].get<double>(), b["q"][3].get<double>());
      const Eigen::Quaterniond ours = a * from_wxyz(frames[k].q_earth_segment[s]) * a.conjugate();
      EXPECT_LT(angle_between_deg(qb, ours), 0.01) << kBvhBoneNames[s] << " frame " << k;
      const auto& p = frames[k].p_earth_segment_m[s];
      const Eigen::Vector3d head(b["head"][0].get<double>(), b["head"][1].get<double>(),
                                 b["head"][2].get<double>());
      EXPECT_LT((head - a * Eigen::Vector3d(p[0], p[1], p[2])).norm(), 2e-4)
          << kBvhBoneNames[s] << " frame " << k;
    }
  }
}

}  // namespace mocap::test
