// BVH: writer output is well formed and round-trips through the reader; foreign files (T-pose
// rest, collars, another channel order) map onto our segments; malformed files are rejected
// with the line.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "mocap/skeleton/bvh.hpp"
#include "mocap/skeleton/skeleton.hpp"
#include "skeleton_test_util.hpp"
#include "take_test_util.hpp"

namespace mocap {
namespace {

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

Eigen::Vector3d vpos(const PoseFrame& f, int s) {
  return Eigen::Vector3d(f.p_earth_segment_m[s][0], f.p_earth_segment_m[s][1],
                         f.p_earth_segment_m[s][2]);
}

TEST(Bvh, EulerZxyRoundTrip) {
  std::mt19937 rng(21);
  for (int k = 0; k < 1000; ++k) {
    const Eigen::Quaterniond q = test::random_rotation(rng);
    const Eigen::Vector3d e = zxy_degrees_from_rotation(q);
    EXPECT_LT(angle_between_deg(rotation_from_zxy_degrees(e[0], e[1], e[2]), q), 1e-9);
  }
  // Gimbal lock (x = 90 deg).
  const Eigen::Quaterniond g = rotation_from_zxy_degrees(30, 90, 20);
  const Eigen::Vector3d e = zxy_degrees_from_rotation(g);
  EXPECT_LT(angle_between_deg(rotation_from_zxy_degrees(e[0], e[1], e[2]), g), 1e-6);
}

TEST(Bvh, WriterFormatAndRoundTrip) {
  const BodyModel model(BodyModelConfig{1.68});
  const std::string path = std::string(MOCAP_BINARY_DIR) + "/test_bvh_roundtrip.bvh";
  std::vector<PoseFrame> frames;
  {
    BvhWriter w(path, model, {.frame_time_s = 0.01});
    frames = test::write_random_take(w, model, 25, 22, 50, 10'000'000);
    EXPECT_EQ(w.frames(), 25);
  }
  const std::string text = read_file(path);
  // Blender's line-oriented rules: '{' alone on its line, root offset zero, Frames patched.
  EXPECT_EQ(text.rfind("HIERARCHY\nROOT Hips\n{\n  OFFSET 0.000000 0.000000 0.000000\n", 0), 0u);
  EXPECT_NE(text.find("JOINT LeftForeArm\n"), std::string::npos);
  EXPECT_NE(text.find("Frames: 25"), std::string::npos);
  EXPECT_NE(text.find("Frame Time: 0.010000000\n"), std::string::npos);
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    if (line.find('{') != std::string::npos || line.find('}') != std::string::npos) {
      EXPECT_EQ(line.find_first_not_of(" {}"), std::string::npos) << line;
    }
  }

  const BvhMotion motion(load_bvh(path));
  ASSERT_EQ(motion.frames(), 25);
  EXPECT_DOUBLE_EQ(motion.frame_time_s(), 0.01);
  for (int s = 0; s < kSegmentCount; ++s) {
    EXPECT_EQ(motion.joint_for_segment()[s], s);  // our writer's order is our segment order
    EXPECT_LT((motion.dimensions().joint_offset_m[s] - model.joint_offset_m(s)).norm(), 1e-6)
        << kSegmentNames[s];
  }
  for (int k = 0; k < 25; ++k) {
    PoseFrame back;
    reset_pose(back);
    motion.to_pose_frame(k, back);
    for (int s = 0; s < kSegmentCount; ++s) {
      EXPECT_LT(angle_between_deg(from_wxyz(back.q_parent_segment[s]),
                                  from_wxyz(frames[k].q_parent_segment[s])),
                1e-3);
      EXPECT_LT(angle_between_deg(from_wxyz(back.q_earth_segment[s]),
                                  from_wxyz(frames[k].q_earth_segment[s])),
                1e-3);
      EXPECT_LT((vpos(back, s) - vpos(frames[k], s)).norm(), 1e-4) << kSegmentNames[s];
    }
  }
}

// A CMU-style file: T-pose rest, collars and two spine joints, X Y Z channel order, inches-ish.
std::string foreign_bvh(std::mt19937& rng, int frames, std::vector<std::string>& zero_joints) {
  struct J {
    const char* name;
    int parent;
    double x, y, z;
    bool end;
  };
  const std::vector<J> js = {
      {"Hips", -1, 0, 0, 0, false},
      {"LHipJoint", 0, 0, 0, 0, false},
      {"LeftUpLeg", 1, 3.5, -1, 0, false},
      {"LeftLeg", 2, 0, -17, 0, false},
      {"LeftFoot", 3, 0, -17, 0, true},
      {"RightUpLeg", 0, -3.5, -1, 0, false},
      {"RightLeg", 5, 0, -17, 0, false},
      {"RightFoot", 6, 0, -17, 0, true},
      {"Spine", 0, 0, 3, 0, false},
      {"Spine1", 8, 0, 6, 0, false},
      {"Neck", 9, 0, 6, 0, false},
      {"Head", 10, 0, 3.5, 0.5, true},
      {"LeftShoulder", 9, 1.5, 5, 0, false},
      {"LeftArm", 12, 5, 0, 0, false},
      {"LeftForeArm", 13, 11, 0, 0, false},
      {"LeftHand", 14, 9, 0, 0, true},
      {"RightShoulder", 9, -1.5, 5, 0, false},
      {"RightArm", 16, -5, 0, 0, false},
      {"RightForeArm", 17, -11, 0, 0, false},
      {"RightHand", 18, -9, 0, 0, true},
  };
  zero_joints = {"LHipJoint", "Spine1", "LeftShoulder", "RightShoulder"};
  std::ostringstream os;
  os << "HIERARCHY\n";
  auto emit = [&](auto&& self, int i, int depth) -> void {
    const std::string ind(depth * 2, ' ');
    os << ind << (i == 0 ? "ROOT " : "JOINT ") << js[i].name << "\n" << ind << "{\n";
    os << ind << "  OFFSET " << js[i].x << " " << js[i].y << " " << js[i].z << "\n";
    os << ind << "  CHANNELS " << (i == 0 ? "6 Xposition Yposition Zposition " : "3 ")
       << "Xrotation Yrotation Zrotation\n";
    for (size_t c = 0; c < js.size(); ++c)
      if (js[c].parent == i) self(self, static_cast<int>(c), depth + 1);
    if (js[i].end)
      os << ind << "  End Site\n"
         << ind << "  {\n"
         << ind << "    OFFSET 0 -2 4\n"
         << ind << "  }\n";
    os << ind << "}\n";
  };
  emit(emit, 0, 0);
  os << "MOTION\nFrames: " << frames << "\nFrame Time: 0.0083333\n";
  std::uniform_real_distribution<double> u(-40, 40);
  for (int k = 0; k < frames; ++k) {
    os << u(rng) << " " << 30 + u(rng) * 0.1 << " " << u(rng);
    // Depth-first emission order equals the order of js here.
    for (size_t i = 0; i < js.size(); ++i) {
      bool zero = false;
      for (const auto& z : zero_joints)
        zero = zero || z == js[i].name;
      for (int c = 0; c < 3; ++c)
        os << " " << (zero ? 0.0 : u(rng));
    }
    os << "\n";
  }
  return os.str();
}

TEST(Bvh, ForeignSkeletonMapsOntoSegments) {
  std::mt19937 rng(23);
  std::vector<std::string> zero;
  const BvhClip clip = parse_bvh(foreign_bvh(rng, 5, zero), "cmu.bvh");
  ASSERT_EQ(clip.frame_count, 5);
  ASSERT_EQ(clip.channel_count, 6 + 3 * 19);
  const double m_per_unit = 0.0254;
  const BvhMotion motion(clip, m_per_unit);
  for (int s = 0; s < kSegmentCount; ++s)
    ASSERT_GE(motion.joint_for_segment()[s], 0) << s;
  EXPECT_EQ(clip.joints[motion.joint_for_segment()[index(Segment::upper_arm_l)]].name, "LeftArm");
  // T-pose rest: the left upper arm bone points along the file's +x (the character's left).
  std::vector<Eigen::Quaterniond> gq;
  std::vector<Eigen::Vector3d> gp;
  const Eigen::Quaterniond c = q_bvh_body();
  for (int k = 0; k < 5; ++k) {
    PoseFrame f;
    reset_pose(f);
    motion.to_pose_frame(k, f);
    clip.global_pose(k, gq, gp);
    for (int s = 0; s < kSegmentCount; ++s) {
      const Eigen::Vector3d file_m = c.conjugate() * gp[motion.joint_for_segment()[s]] * m_per_unit;
      EXPECT_LT((vpos(f, s) - file_m).norm(), 1e-4) << kSegmentNames[s] << " frame " << k;
    }
  }
  // The N-pose convention: a frame with all rotations zero (T-pose) gives arms raised sideways.
  std::string t_pose = foreign_bvh(rng, 1, zero);
  const size_t motion_at = t_pose.find("Frame Time: 0.0083333\n") + 22;
  t_pose = t_pose.substr(0, motion_at);
  t_pose += "0 30 0 0 0 0";
  for (int i = 0; i < 19 * 3; ++i)
    t_pose += " 0";
  const BvhMotion tm(parse_bvh(t_pose));
  std::array<Eigen::Quaterniond, kSegmentCount> q;
  Eigen::Vector3d root;
  tm.frame(0, q, root);
  EXPECT_LT(angle_between_deg(q[index(Segment::upper_arm_l)], axis_rotation(0, M_PI / 2)), 1e-6);
  EXPECT_LT(angle_between_deg(q[index(Segment::upper_arm_r)], axis_rotation(0, -M_PI / 2)), 1e-6);
  EXPECT_LT(angle_between_deg(q[index(Segment::thigh_l)], Eigen::Quaterniond::Identity()), 1e-6);
}

TEST(Bvh, MalformedFilesAreRejectedWithTheLine) {
  auto err = [](std::string_view t) {
    try {
      parse_bvh(t, "x.bvh");
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string head =
      "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n}\n";
  EXPECT_EQ(err(head + "MOTION\nFrames: 1\nFrame Time: 0.1\n1 2 3\n"), "no error");
  EXPECT_NE(err("HIERARCH\n").find("x.bvh:1: expected 'HIERARCHY'"), std::string::npos);
  EXPECT_NE(err(head + "MOTION\nFrames: 2\nFrame Time: 0.1\n1 2 3\n").find("Frames says 2"),
            std::string::npos);
  EXPECT_NE(err(head + "MOTION\nFrames: 1\nFrame Time: 0.1\n1 2\n")
                .find("x.bvh:10: frame data is not a whole"),
            std::string::npos);
  EXPECT_NE(err(head + "MOTION\nFrames: 1\nFrame Time: 0.1\n1 nan 3\n")
                .find("x.bvh:10: expected a number"),
            std::string::npos);
  EXPECT_NE(err("HIERARCHY\nROOT Hips\n{\n  CHANNELS 2 Zrotation Wrotation\n}\n")
                .find("x.bvh:4: unknown channel 'Wrotation'"),
            std::string::npos);
  EXPECT_NE(err("HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0\n").find("x.bvh:5: unexpected end of file"),
            std::string::npos);
  EXPECT_NE(
      err(head + "MOTION\nFrames: 1\nFrame Time: -1\n1 2 3\n").find("Frame Time must be positive"),
      std::string::npos);
  std::string deep = "HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\n";
  for (int i = 0; i < 200; ++i)
    deep += "JOINT j\n{\nOFFSET 0 0 0\n";
  EXPECT_NE(err(deep).find("nested too deeply"), std::string::npos);
  // An interrupted writer leaves "Frames: 0": the data is trusted.
  EXPECT_EQ(parse_bvh(head + "MOTION\nFrames: 0\nFrame Time: 0.1\n1 2 3\n4 5 6\n").frame_count, 2);
  EXPECT_THROW(load_bvh("/nonexistent.bvh"), std::runtime_error);
}

}  // namespace
}  // namespace mocap
