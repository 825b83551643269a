// BVH writer proven against a real third-party reader: Blender's importer (headless) loads our
// file, and the bone rotations and positions it reconstructs must equal ours.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "blender_test_util.hpp"
#include "mocap/skeleton/bvh.hpp"
#include "take_test_util.hpp"

namespace mocap {
namespace {

TEST(BvhBlender, BlenderImportsOurRotationsAndPositions) {
  if (!test::have_blender()) GTEST_SKIP() << "blender not installed";
  const BodyModel model(BodyModelConfig{1.72});
  const std::string dir = MOCAP_BINARY_DIR;
  const std::string bvh = dir + "/test_blender.bvh", json = dir + "/test_blender.json";
  std::vector<PoseFrame> frames;
  {
    BvhWriter w(bvh, model, {.frame_time_s = 1.0 / 30});
    frames = test::write_blender_take(w, model, 4);
  }
  nlohmann::json j;
  ASSERT_TRUE(test::run_blender_dump("blender_bvh_dump.py", bvh + " " + json, json,
                                     dir + "/test_blender.log", &j));
  ASSERT_EQ(j["frames"].size(), frames.size());
  test::expect_blender_bones_match(j["frames"], frames);
}

}  // namespace
}  // namespace mocap
