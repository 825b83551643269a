// glTF writer: the .glb container and its JSON checked by the format's rules (chunks, accessors
// within their bufferViews, min/max on the time accessor), then proven against a real
// third-party reader: Blender's glTF importer (headless) loads our file, and the armature, the
// frame count and the bone rotations and positions it reconstructs must equal ours.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>

#include "mocap/skeleton/bvh.hpp"
#include "mocap/skeleton/gltf.hpp"
#include "mocap/skeleton/skeleton.hpp"
#include "skeleton_test_util.hpp"

namespace mocap {
namespace {

uint32_t le32(const std::vector<uint8_t>& b, std::size_t at) {
  return uint32_t(b[at]) | uint32_t(b[at + 1]) << 8 | uint32_t(b[at + 2]) << 16 |
         uint32_t(b[at + 3]) << 24;
}

/// A few random solved poses written to `path` at 30 Hz.
std::vector<PoseFrame> write_take(const std::string& path, const BodyModel& model, int count) {
  std::mt19937 rng(31);
  Skeleton sk(model, default_joint_limits(), RigMapping::full());
  std::vector<PoseFrame> frames;
  GltfWriter w(path, model, {.frame_time_s = 1.0 / 30});
  for (int k = 0; k < count; ++k) {
    const auto pose = test::random_pose(rng, 70);
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

}  // namespace

TEST(Gltf, BinaryContainerAndJsonFollowTheFormat) {
  const BodyModel model(BodyModelConfig{1.72});
  const std::string path = std::string(MOCAP_BINARY_DIR) + "/test_gltf_format.glb";
  const auto frames = write_take(path, model, 5);
  std::ifstream in(path, std::ios::binary);
  const std::vector<uint8_t> b((std::istreambuf_iterator<char>(in)), {});
  ASSERT_GE(b.size(), 28u);
  EXPECT_EQ(le32(b, 0), 0x46546C67u);  // "glTF"
  EXPECT_EQ(le32(b, 4), 2u);
  EXPECT_EQ(le32(b, 8), b.size());
  const uint32_t json_len = le32(b, 12);
  EXPECT_EQ(le32(b, 16), 0x4E4F534Au);
  EXPECT_EQ(json_len % 4, 0u);
  const std::size_t bin_at = 20 + json_len;
  ASSERT_LE(bin_at + 8, b.size());
  const uint32_t bin_len = le32(b, bin_at);
  EXPECT_EQ(le32(b, bin_at + 4), 0x004E4942u);
  EXPECT_EQ(bin_at + 8 + bin_len, b.size());
  const auto j = nlohmann::json::parse(b.begin() + 20, b.begin() + 20 + json_len);
  EXPECT_EQ(j["asset"]["version"], "2.0");
  ASSERT_EQ(j["nodes"].size(), static_cast<std::size_t>(kSegmentCount));
  for (int s = 0; s < kSegmentCount; ++s)
    EXPECT_EQ(j["nodes"][s]["name"], std::string(kBvhBoneNames[s]));
  EXPECT_EQ(j["skins"][0]["joints"].size(), static_cast<std::size_t>(kSegmentCount));
  EXPECT_LE(j["buffers"][0]["byteLength"].get<std::size_t>(), bin_len);
  // Every accessor lies within its bufferView, every view within the buffer, 4-byte aligned.
  const std::map<std::string, int> comps = {{"SCALAR", 1}, {"VEC3", 3}, {"VEC4", 4}, {"MAT4", 16}};
  for (const auto& a : j["accessors"]) {
    const auto& v = j["bufferViews"][a["bufferView"].get<int>()];
    EXPECT_EQ(a["componentType"], 5126);
    const std::size_t bytes = a["count"].get<std::size_t>() * comps.at(a["type"]) * 4;
    EXPECT_EQ(v["byteLength"].get<std::size_t>(), bytes);
    EXPECT_EQ(v["byteOffset"].get<std::size_t>() % 4, 0u);
    EXPECT_LE(v["byteOffset"].get<std::size_t>() + bytes,
              j["buffers"][0]["byteLength"].get<std::size_t>());
  }
  ASSERT_EQ(j["animations"].size(), 1u);
  const auto& anim = j["animations"][0];
  EXPECT_EQ(anim["channels"].size(), static_cast<std::size_t>(kSegmentCount + 1));
  const auto& time = j["accessors"][anim["samplers"][0]["input"].get<int>()];
  EXPECT_EQ(time["count"], frames.size());
  EXPECT_FLOAT_EQ(time["min"][0].get<float>(), 0.f);
  EXPECT_FLOAT_EQ(time["max"][0].get<float>(), 4.f / 30);
  for (const auto& ch : anim["channels"]) {
    const auto& smp = anim["samplers"][ch["sampler"].get<int>()];
    EXPECT_EQ(smp["input"], anim["samplers"][0]["input"]);
    EXPECT_EQ(j["accessors"][smp["output"].get<int>()]["count"], frames.size());
    const std::string path_kind = ch["target"]["path"];
    EXPECT_TRUE(path_kind == "rotation" ||
                (path_kind == "translation" && ch["target"]["node"] == 0));
  }
}

TEST(GltfBlender, BlenderImportsOurBonesFramesRotationsAndPositions) {
  if (std::system("command -v blender >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "blender not installed";
  const BodyModel model(BodyModelConfig{1.72});
  const std::string dir = MOCAP_BINARY_DIR;
  const std::string glb = dir + "/test_blender.glb", json = dir + "/test_blender_gltf.json";
  const auto frames = write_take(glb, model, 4);
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
