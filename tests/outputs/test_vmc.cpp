// VMC tests: the frame conversion (T-pose rest, Unity left-handed axes, local rotations and
// positions rebuilt into world space), bundle framing on a real UDP socket, and liblo's oscdump
// as a real third-party receiver checking names, type tags and values.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "../common/free_port.hpp"
#include "../common/oscdump_capture.hpp"
#include "mocap/outputs/vmc.hpp"

using namespace mocap;
using mocap::outputs::kVmcBoneCount;
using mocap::outputs::vmc_pose_from_frame;
using mocap::outputs::VmcPose;
using mocap::outputs::VmcSender;

namespace {

const std::set<std::string> kHumanBodyBones = {
    "Hips",          "LeftUpperLeg", "RightUpperLeg", "LeftLowerLeg",  "RightLowerLeg",
    "LeftFoot",      "RightFoot",    "Spine",         "Chest",         "UpperChest",
    "Neck",          "Head",         "LeftShoulder",  "RightShoulder", "LeftUpperArm",
    "RightUpperArm", "LeftLowerArm", "RightLowerArm", "LeftHand",      "RightHand"};

Eigen::Quaterniond unity_q(const std::array<float, 4>& q) {  // x, y, z, w
  return Eigen::Quaterniond(q[3], q[0], q[1], q[2]);
}
Eigen::Vector3d unity_v(const std::array<float, 3>& p) {
  return {p[0], p[1], p[2]};
}
/// Our ENU/body axes to Unity axes (x right, y up, z forward).
Eigen::Vector3d to_unity(const Eigen::Vector3d& v) {
  return {-v.y(), v.z(), v.x()};
}

Eigen::Quaterniond random_q(std::mt19937& rng) {
  std::normal_distribution<double> n;
  return Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized();
}

PoseFrame random_frame(std::mt19937& rng) {
  PoseFrame f;
  reset_pose(f);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int s = 0; s < kSegmentCount; ++s) {
    const Eigen::Quaterniond q = random_q(rng);
    f.q_earth_segment[s] = {float(q.w()), float(q.x()), float(q.y()), float(q.z())};
    f.p_earth_segment_m[s] = {float(u(rng)), float(u(rng)), float(1 + u(rng))};
  }
  return f;
}

int bone_index(const VmcPose& p, std::string_view name) {
  for (int i = 0; i < kVmcBoneCount; ++i)
    if (p.bones[i].name == name) return i;
  return -1;
}

// Unity parent of each bone we send (HumanBodyBones hierarchy, UpperChest present).
const std::map<std::string, std::string> kParent = {{"Spine", "Hips"},
                                                    {"Chest", "Spine"},
                                                    {"UpperChest", "Chest"},
                                                    {"Neck", "UpperChest"},
                                                    {"Head", "Neck"},
                                                    {"LeftShoulder", "UpperChest"},
                                                    {"LeftUpperArm", "LeftShoulder"},
                                                    {"LeftLowerArm", "LeftUpperArm"},
                                                    {"LeftHand", "LeftLowerArm"},
                                                    {"RightShoulder", "UpperChest"},
                                                    {"RightUpperArm", "RightShoulder"},
                                                    {"RightLowerArm", "RightUpperArm"},
                                                    {"RightHand", "RightLowerArm"},
                                                    {"LeftUpperLeg", "Hips"},
                                                    {"LeftLowerLeg", "LeftUpperLeg"},
                                                    {"LeftFoot", "LeftLowerLeg"},
                                                    {"RightUpperLeg", "Hips"},
                                                    {"RightLowerLeg", "RightUpperLeg"},
                                                    {"RightFoot", "RightLowerLeg"}};

/// World rotation and position of a bone in Unity, rebuilt from root + local transforms the
/// way a receiver applies them.
void unity_world(const VmcPose& p, const std::string& name, Eigen::Quaterniond& q,
                 Eigen::Vector3d& pos) {
  const int i = bone_index(p, name);
  if (name == "Hips") {
    const Eigen::Quaterniond root = unity_q(p.root_q);
    q = root * unity_q(p.bones[i].q);
    pos = unity_v(p.root_p) + root * unity_v(p.bones[i].p);
    return;
  }
  Eigen::Quaterniond qp;
  Eigen::Vector3d pp;
  unity_world(p, kParent.at(name), qp, pp);
  q = qp * unity_q(p.bones[i].q);
  pos = pp + qp * unity_v(p.bones[i].p);
}

}  // namespace

TEST(VmcPose, NPoseGivesTPoseRestExceptArmsSwungDown) {
  PoseFrame f;
  reset_pose(f);
  VmcPose p;
  ASSERT_TRUE(vmc_pose_from_frame(f, p));
  const double h = std::sqrt(0.5);
  for (const auto& b : p.bones) {
    ASSERT_TRUE(kHumanBodyBones.count(std::string(b.name))) << b.name;
    Eigen::Vector4d expect(0, 0, 0, 1);
    // Upper arms: the only bones whose rest differs (a T-pose arm points sideways, ours hangs).
    if (b.name == "LeftUpperArm") expect = {0, 0, h, h};    // +90 about z: -x (left) -> down
    if (b.name == "RightUpperArm") expect = {0, 0, -h, h};  // -90 about z: +x (right) -> down
    for (int k = 0; k < 4; ++k)
      EXPECT_NEAR(b.q[k], expect[k], 1e-6) << b.name << " " << k;
  }
  // Rotating the T-pose left arm direction (-x) by the sent rotation points it down.
  const Eigen::Vector3d down =
      unity_q(p.bones[bone_index(p, "LeftUpperArm")].q) * Eigen::Vector3d(-1, 0, 0);
  EXPECT_NEAR((down - Eigen::Vector3d(0, -1, 0)).norm(), 0, 1e-6);
}

TEST(VmcPose, TurningLeftIsANegativeRotationAboutUnityUp) {
  PoseFrame f;
  reset_pose(f);
  const double h = std::sqrt(0.5);
  for (auto& q : f.q_earth_segment)
    q = {float(h), 0, 0, float(h)};  // +90 about ENU z (left)
  VmcPose p;
  ASSERT_TRUE(vmc_pose_from_frame(f, p));
  const auto& hips = p.bones[bone_index(p, "Hips")];
  EXPECT_NEAR(hips.q[1], -h, 1e-6);
  EXPECT_NEAR(hips.q[3], h, 1e-6);
  // Forward (+z in Unity) turned left points to the character's left (-x).
  const Eigen::Vector3d fwd = unity_q(hips.q) * Eigen::Vector3d(0, 0, 1);
  EXPECT_NEAR((fwd - Eigen::Vector3d(-1, 0, 0)).norm(), 0, 1e-6);
  // Children turn with the pelvis: their local rotations stay at rest.
  EXPECT_NEAR(p.bones[bone_index(p, "Spine")].q[3], 1, 1e-6);
}

TEST(VmcPose, RebuiltUnityWorldMatchesOurSegmentsForRandomPoses) {
  std::mt19937 rng(7);
  // Rest direction of a bone in our N-pose (segment axes) and in the Unity T-pose.
  struct Dir {
    std::string bone;
    int segment;
    Eigen::Vector3d ours_npose, unity_tpose;
  };
  const std::vector<Dir> dirs = {
      {"Spine", index(Segment::torso), {0, 0, 1}, {0, 1, 0}},
      {"Head", index(Segment::head), {1, 0, 0}, {0, 0, 1}},
      {"LeftUpperArm", index(Segment::upper_arm_l), {0, 0, -1}, {-1, 0, 0}},
      {"LeftHand", index(Segment::hand_l), {0, 0, -1}, {-1, 0, 0}},
      {"RightLowerArm", index(Segment::forearm_r), {0, 0, -1}, {1, 0, 0}},
      {"RightLowerArm", index(Segment::forearm_r), {1, 0, 0}, {0, 0, 1}},
      {"LeftLowerLeg", index(Segment::shank_l), {0, 0, -1}, {0, -1, 0}},
      {"RightFoot", index(Segment::foot_r), {1, 0, 0}, {0, 0, 1}},
  };
  for (int trial = 0; trial < 50; ++trial) {
    const PoseFrame f = random_frame(rng);
    VmcPose p;
    ASSERT_TRUE(vmc_pose_from_frame(f, p));
    for (const auto& d : dirs) {
      Eigen::Quaterniond qw;
      Eigen::Vector3d pw;
      unity_world(p, d.bone, qw, pw);
      const auto& q = f.q_earth_segment[d.segment];
      const Eigen::Vector3d ours =
          Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized() * d.ours_npose;
      EXPECT_NEAR((qw * d.unity_tpose - to_unity(ours)).norm(), 0, 1e-5) << d.bone;
      const auto& pe = f.p_earth_segment_m[d.segment];
      EXPECT_NEAR((pw - to_unity(Eigen::Vector3d(pe[0], pe[1], pe[2]))).norm(), 0, 1e-5) << d.bone;
    }
  }
}

TEST(VmcPose, NonFiniteFrameIsRefused) {
  PoseFrame f;
  reset_pose(f);
  f.q_earth_segment[5][2] = std::nanf("");
  VmcPose p;
  EXPECT_FALSE(vmc_pose_from_frame(f, p));
  VmcSender s;
  std::string err;
  ASSERT_TRUE(s.open({}, &err)) << err;
  EXPECT_FALSE(s.publish(f));
  EXPECT_EQ(s.stats().frames_invalid, 1u);
  EXPECT_EQ(s.stats().datagrams_sent, 0u);
}

namespace {

int udp_socket_on_free_port(uint16_t& port) {
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t len = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  port = ntohs(a.sin_port);
  return fd;
}

uint32_t be32(const uint8_t* p) {
  return (uint32_t(p[0]) << 24) | (uint32_t(p[1]) << 16) | (uint32_t(p[2]) << 8) | p[3];
}

PoseFrame moving_frame(int k) {
  std::mt19937 rng(static_cast<unsigned>(100 + k));
  PoseFrame f = random_frame(rng);
  f.frame = static_cast<uint64_t>(k);
  f.t_ns = 1'000'000'000 + int64_t{k} * 20'000'000;  // 50 Hz
  f.flags = kFrameCalibrated;
  return f;
}

}  // namespace

TEST(VmcSender, BundlesStayWithinTheDatagramLimitAndCarryEveryMessage) {
  for (std::size_t limit : {std::size_t{1500}, std::size_t{600}}) {
    uint16_t port = 0;
    const int rx = udp_socket_on_free_port(port);
    VmcSender s;
    std::string err;
    VmcSender::Options opt;
    opt.port = port;
    opt.max_datagram = limit;
    ASSERT_TRUE(s.open(opt, &err)) << err;
    constexpr int kFrames = 5;
    for (int k = 0; k < kFrames; ++k)
      ASSERT_TRUE(s.publish(moving_frame(k)));
    EXPECT_EQ(s.stats().frames_sent, static_cast<uint64_t>(kFrames));
    std::map<std::string, int> addresses;
    uint64_t datagrams = 0;
    uint8_t buf[65536];
    pollfd pfd{rx, POLLIN, 0};
    while (::poll(&pfd, 1, 200) > 0) {
      const ssize_t n = ::recv(rx, buf, sizeof buf, 0);
      ASSERT_GT(n, 16);
      ++datagrams;
      EXPECT_LE(static_cast<std::size_t>(n), limit);
      ASSERT_EQ(std::memcmp(buf, "#bundle\0", 8), 0);
      EXPECT_EQ(be32(buf + 8), 0u);  // timetag 1 = immediately
      EXPECT_EQ(be32(buf + 12), 1u);
      std::size_t off = 16;
      while (off < static_cast<std::size_t>(n)) {
        const uint32_t size = be32(buf + off);
        ASSERT_EQ(size % 4, 0u);
        ASSERT_LE(off + 4 + size, static_cast<std::size_t>(n));
        ASSERT_EQ(buf[off + 4], '/');
        addresses[reinterpret_cast<const char*>(buf + off + 4)]++;
        off += 4 + size;
      }
      EXPECT_EQ(off, static_cast<std::size_t>(n));
    }
    ::close(rx);
    EXPECT_EQ(datagrams, s.stats().datagrams_sent);
    EXPECT_GT(datagrams, static_cast<uint64_t>(kFrames));  // 20 bones do not fit in one
    EXPECT_LE(s.stats().max_datagram_bytes, limit);
    EXPECT_EQ(addresses["/VMC/Ext/Bone/Pos"], kFrames * kVmcBoneCount);
    EXPECT_EQ(addresses["/VMC/Ext/Root/Pos"], kFrames);
    EXPECT_EQ(addresses["/VMC/Ext/OK"], kFrames);
    EXPECT_EQ(addresses["/VMC/Ext/T"], kFrames);
  }
}

TEST(VmcSender, RateLimitSkipsFramesCloserThanTheInterval) {
  uint16_t port = 0;
  const int rx = udp_socket_on_free_port(port);
  VmcSender s;
  std::string err;
  VmcSender::Options opt;
  opt.port = port;
  opt.min_interval_ms = 10;
  ASSERT_TRUE(s.open(opt, &err));
  PoseFrame f;
  reset_pose(f);
  for (int k = 0; k < 20; ++k) {
    f.t_ns = int64_t{k} * 4'000'000;  // 250 Hz in: about every third frame goes out
    s.publish(f);
  }
  EXPECT_EQ(s.stats().frames_sent, 7u);  // t = 0, 12, 24, 36, 48, 60, 72 ms
  EXPECT_EQ(s.stats().frames_rate_limited, 13u);
  ::close(rx);
  opt.host = "localhost-not-an-ip";
  EXPECT_FALSE(s.open(opt, &err));
  EXPECT_NE(err.find("localhost-not-an-ip"), std::string::npos);
}

TEST(VmcSender, OscdumpReceivesBonesWithUnityNamesFloatArgsAndOurValues) {
  if (!test::have_oscdump()) GTEST_SKIP() << "oscdump (liblo-tools) missing";
  const auto port = static_cast<uint16_t>(test::free_loopback_port(SOCK_DGRAM));
  VmcSender s;
  std::string err;
  VmcSender::Options opt;
  opt.port = port;
  ASSERT_TRUE(s.open(opt, &err)) << err;
  const test::OscdumpCapture cap =
      test::capture_oscdump(port, [&](int k) { s.publish(moving_frame(k)); });
  const std::string& text = cap.text;
  ASSERT_GT(cap.frames_before_first_output, 0) << "oscdump printed nothing";

  // Lines: "<timetag> <address> <types> args...". Group them into frames ending at /VMC/Ext/T.
  std::istringstream in(text);
  std::string line;
  std::vector<std::string> group;
  int complete_frames = 0;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string tt, address, types;
    ls >> tt >> address >> types;
    group.push_back(line);
    if (address != "/VMC/Ext/T") continue;
    ASSERT_EQ(types, "f") << line;
    double t = 0;
    ls >> t;
    const int frame = static_cast<int>(std::lround(t / 0.02));
    // A frame group is complete if its Root, 20 bones and OK all arrived (UDP may lose the
    // first ones while oscdump starts).
    if (group.size() == 2 + kVmcBoneCount + 1) {
      VmcPose expect;
      ASSERT_TRUE(vmc_pose_from_frame(moving_frame(frame), expect));
      std::set<std::string> names;
      for (std::size_t i = 0; i + 2 < group.size(); ++i) {
        std::istringstream gs(group[i]);
        std::string gtt, gaddr, gtypes, name;
        gs >> gtt >> gaddr >> gtypes >> name;
        ASSERT_EQ(gtypes, "sfffffff") << group[i];
        ASSERT_GE(name.size(), 2u);
        name = name.substr(1, name.size() - 2);  // strip quotes
        float v[7];
        for (float& x : v)
          gs >> x;
        ASSERT_FALSE(gs.fail()) << group[i];
        std::array<float, 3> p{};
        std::array<float, 4> q{};
        if (i == 0) {
          ASSERT_EQ(gaddr, "/VMC/Ext/Root/Pos");
          ASSERT_EQ(name, "root");
          p = expect.root_p;
          q = expect.root_q;
        } else {
          ASSERT_EQ(gaddr, "/VMC/Ext/Bone/Pos");
          ASSERT_TRUE(kHumanBodyBones.count(name)) << name;
          names.insert(name);
          const auto& b = expect.bones[bone_index(expect, name)];
          p = b.p;
          q = b.q;
        }
        for (int c = 0; c < 3; ++c)
          EXPECT_NEAR(v[c], p[c], 2e-6) << group[i];
        for (int c = 0; c < 4; ++c)
          EXPECT_NEAR(v[3 + c], q[c], 2e-6) << group[i];
      }
      EXPECT_EQ(names.size(), static_cast<std::size_t>(kVmcBoneCount));
      std::istringstream ok(group[group.size() - 2]);
      std::string ott, oaddr, otypes;
      int loaded = -1, calib = -1;
      ok >> ott >> oaddr >> otypes >> loaded >> calib;
      EXPECT_EQ(oaddr, "/VMC/Ext/OK");
      EXPECT_EQ(otypes, "iii");
      EXPECT_EQ(loaded, 1);
      EXPECT_EQ(calib, 3);
      ++complete_frames;
    }
    group.clear();
  }
  EXPECT_GE(complete_frames, 3) << text.substr(0, 2000);
}
