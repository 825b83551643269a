// BVH writer proven against a real third-party reader: Blender's importer (headless) loads our
// file, and the bone rotations and positions it reconstructs must equal ours.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>

#include "mocap/skeleton/bvh.hpp"
#include "mocap/skeleton/skeleton.hpp"
#include "skeleton_test_util.hpp"

namespace mocap {
namespace {

TEST(BvhBlender, BlenderImportsOurRotationsAndPositions) {
  if (std::system("command -v blender >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "blender not installed";
  std::mt19937 rng(31);
  const BodyModel model(BodyModelConfig{1.72});
  Skeleton sk(model, default_joint_limits(), RigMapping::full());
  const std::string dir = MOCAP_BINARY_DIR;
  const std::string bvh = dir + "/test_blender.bvh", json = dir + "/test_blender.json";
  std::vector<PoseFrame> frames;
  {
    BvhWriter w(bvh, model, {.frame_time_s = 1.0 / 30});
    for (int k = 0; k < 4; ++k) {
      const auto pose = test::random_pose(rng, 70);
      for (int s = 0; s < kSegmentCount; ++s)
        sk.set_sensor_orientation(s, pose[s], k * 33'000'000LL);
      PoseFrame f;
      reset_pose(f);
      sk.solve(f);
      w.write_frame(f);
      frames.push_back(f);
    }
  }
  std::remove(json.c_str());
  const std::string cmd = "blender -b --factory-startup --python-exit-code 1 --python " +
                          std::string(MOCAP_SOURCE_DIR) +
                          "/tests/skeleton/blender_bvh_dump.py -- " + bvh + " " + json + " >" +
                          dir + "/test_blender.log 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << "blender failed; see " << dir << "/test_blender.log";
  std::ifstream in(json);
  ASSERT_TRUE(in) << "no output from blender";
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_EQ(j["frames"].size(), frames.size());
  // Blender's armature space = BVH axes turned +90 deg about x (BVH y up -> Blender z up).
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

}  // namespace
}  // namespace mocap
