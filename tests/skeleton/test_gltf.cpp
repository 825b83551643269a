// glTF writer: the .glb container and its JSON checked by the format's rules (the 12-byte header,
// JSON and BIN chunks with their lengths, every accessor within its bufferView and every view
// within the buffer, 4-byte alignment, min/max on the time accessor, the animation's channels).
#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>

#include "mocap/skeleton/bvh.hpp"
#include "take_test_util.hpp"

namespace mocap {
namespace {

uint32_t le32(const std::vector<uint8_t>& b, std::size_t at) {
  return uint32_t(b[at]) | uint32_t(b[at + 1]) << 8 | uint32_t(b[at + 2]) << 16 |
         uint32_t(b[at + 3]) << 24;
}

}  // namespace

TEST(Gltf, BinaryContainerAndJsonFollowTheFormat) {
  const BodyModel model(BodyModelConfig{1.72});
  const std::string path = std::string(MOCAP_BINARY_DIR) + "/test_gltf_format.glb";
  const auto frames = test::write_gltf_take(path, model, 5);
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

}  // namespace mocap
