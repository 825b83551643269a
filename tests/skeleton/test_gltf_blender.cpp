// glTF writer proven against a real third-party reader: Blender's glTF importer (headless) loads
// our file, and the armature, the frame count and the bone rotations and positions it
// reconstructs must equal ours.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "blender_test_util.hpp"
#include "mocap/skeleton/bvh.hpp"
#include "take_test_util.hpp"

namespace mocap {

TEST(GltfBlender, BlenderImportsOurBonesFramesRotationsAndPositions) {
  if (!test::have_blender()) GTEST_SKIP() << "blender not installed";
  const BodyModel model(BodyModelConfig{1.72});
  const std::string dir = MOCAP_BINARY_DIR;
  const std::string glb = dir + "/test_blender.glb", json = dir + "/test_blender_gltf.json";
  const auto frames = test::write_gltf_take(glb, model, 4);
  nlohmann::json j;
  ASSERT_TRUE(test::run_blender_dump("blender_gltf_dump.py", glb + " " + json + " 30", json,
                                     dir + "/test_blender_gltf.log", &j));
  ASSERT_EQ(j["bones"].size(), static_cast<std::size_t>(kSegmentCount));
  for (int s = 1; s < kSegmentCount; ++s)
    EXPECT_EQ(j["parents"][std::string(kBvhBoneNames[s])],
              std::string(kBvhBoneNames[kSegmentParent[s]]));
  EXPECT_EQ(j["actions"], 1);
  ASSERT_EQ(j["frames"].size(), frames.size());
  test::expect_blender_bones_match(j["frames"], frames);
}

}  // namespace mocap
