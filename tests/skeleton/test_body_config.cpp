// Body model config: TOML overrides on top of the anthropometric model, the shipped files, errors.
#include <gtest/gtest.h>

#include "mocap/skeleton/body_model.hpp"
#include "mocap/skeleton/joint_limits.hpp"

namespace mocap {
namespace {

TEST(BodyConfig, OverridesOnTopOfHeight) {
  const BodyModelConfig cfg = parse_body_config(
      "height_m = 1.6\n[segment.forearm_l]\njoint_offset_m = [0, 0, -0.33]\n"
      "end_offset_m = [0.0, 0, -0.2]\n");
  const BodyModel m(cfg);
  EXPECT_EQ(m.height_m(), 1.6);
  EXPECT_EQ(m.joint_offset_m(index(Segment::forearm_l)), Eigen::Vector3d(0, 0, -0.33));
  EXPECT_EQ(m.end_offset_m(index(Segment::forearm_l)), Eigen::Vector3d(0, 0, -0.2));
  EXPECT_EQ(m.joint_offset_m(index(Segment::forearm_r)),
            body_dimensions_from_height(1.6).joint_offset_m[index(Segment::forearm_r)]);
  EXPECT_EQ(m.parent(index(Segment::hand_l)), index(Segment::forearm_l));
  EXPECT_NEAR(m.pelvis_height_m(), 0.53 * 1.6, 1e-12);
}

TEST(BodyConfig, ShippedFilesParse) {
  const BodyModel m(load_body_config(std::string(MOCAP_SOURCE_DIR) + "/config/body/default.toml"));
  EXPECT_EQ(m.height_m(), 1.75);
  EXPECT_NO_THROW(validate(parse_joint_limits("")));
}

TEST(BodyConfig, ErrorsNameFileLineAndProblem) {
  auto err = [](std::string_view t) {
    try {
      parse_body_config(t, "body.toml");
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(err("height_m = 7\n").find("body.toml:1:"), std::string::npos);
  EXPECT_NE(err("height_m = 7\n").find("out of range"), std::string::npos);
  EXPECT_NE(err("height = 1.7\n").find("unknown key 'height'"), std::string::npos);
  EXPECT_NE(err("[segment.wing_l]\n").find("unknown segment 'wing_l'"), std::string::npos);
  EXPECT_NE(err("[segment.head]\njoint_offset_m = [0, 0]\n").find("body.toml:2:"),
            std::string::npos);
  EXPECT_NE(err("[segment.head]\njoint_offset_m = [0, 0, nan]\n").find("out of range"),
            std::string::npos);
  EXPECT_THROW(load_body_config("/nonexistent/body.toml"), std::runtime_error);
}

}  // namespace
}  // namespace mocap
