// glTF writer proven against a real third-party reader: Blender's glTF importer (headless) loads
// our file, and the armature, the frame count and the bone rotations and positions it
// reconstructs must equal ours.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>

#include "gltf_test_util.hpp"
#include "mocap/skeleton/bvh.hpp"

namespace mocap {

TEST(GltfBlender, BlenderImportsOurBonesFramesRotationsAndPositions) {
  if (std::system("command -v blender >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "blender not installed";
  const BodyModel model(BodyModelConfig{1.72});
  const std::string dir = MOCAP_BINARY_DIR;
  const std::string glb = dir + "/test_blender.glb", json = dir + "/test_blender_gltf.json";
  const auto frames = test::write_gltf_take(glb, model, 4);
  std::remove(json.c_str());
  const std::string cmd = "blender -b --factory-startup --python-exit-code 1 --python " +
                          std::string(MOCAP_SOURCE_DIR) +
                          "/tests/skeleton/blender_gltf_dump.py -- " + glb + " " + json + " 30 >" +
                          dir + "/test_blender_gltf.log 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0)
      << "blender failed; see " << dir << "/test_blender_gltf.log";
  std::ifstream in(json);
  ASSERT_TRUE(in) << "no output from blender";
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_EQ(j["bones"].size(), static_cast<std::size_t>(kSegmentCount));
  for (int s = 1; s < kSegmentCount; ++s)
    EXPECT_EQ(j["parents"][std::string(kBvhBoneNames[s])],
              std::string(kBvhBoneNames[kSegmentParent[s]]));
  EXPECT_EQ(j["actions"], 1);
  ASSERT_EQ(j["frames"].size(), frames.size());
  // Blender's world = glTF axes turned +90 deg about x (glTF y up -> Blender z up).
  const Eigen::Quaterniond a = axis_rotation(0, M_PI / 2) * q_bvh_body();
  for (size_t k = 0; k < frames.size(); ++k) {
    const auto& fb = j["frames"][k];
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

}  // namespace mocap
