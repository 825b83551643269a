// VRChat OSC trackers: Unity Euler angles (Z, X, Y order) of known rotations, the conversion of
// our ENU segments to Unity's left-handed Y-up world, height scaling, the rate limit, and liblo's
// oscdump as a real receiver checking addresses, type tags and the values of a known pose.
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
#include <sstream>
#include <string>

#include "../common/free_port.hpp"
#include "../common/oscdump_capture.hpp"
#include "mocap/core/units.hpp"
#include "mocap/outputs/vrchat.hpp"

using namespace mocap;
using mocap::outputs::unity_euler_deg;
using mocap::outputs::vrchat_tracker_from_frame;
using mocap::outputs::VrchatSender;
using mocap::outputs::VrchatTracker;

namespace {

constexpr double kDeg = kRadPerDeg;

void set_segment(PoseFrame& f, Segment s, const Eigen::Quaterniond& q,
                 const Eigen::Vector3d& p = Eigen::Vector3d::Zero()) {
  f.q_earth_segment[index(s)] = {float(q.w()), float(q.x()), float(q.y()), float(q.z())};
  f.p_earth_segment_m[index(s)] = {float(p.x()), float(p.y()), float(p.z())};
}

VrchatTracker tracker(const Eigen::Quaterniond& q_earth, const Eigen::Vector3d& p = {0, 0, 0},
                      double scale = 1.0) {
  PoseFrame f;
  reset_pose(f);
  set_segment(f, Segment::pelvis, q_earth, p);
  VrchatTracker t;
  EXPECT_TRUE(vrchat_tracker_from_frame(f, index(Segment::pelvis), scale, t));
  return t;
}

/// Unity's Quaternion.Euler(x, y, z): z first, then x, then y (about the fixed world axes).
Eigen::Quaterniond unity_from_euler(const std::array<float, 3>& e) {
  return Eigen::AngleAxisd(e[1] * kDeg, Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(e[0] * kDeg, Eigen::Vector3d::UnitX()) *
         Eigen::AngleAxisd(e[2] * kDeg, Eigen::Vector3d::UnitZ());
}

void expect_euler(const std::array<float, 3>& got, double x, double y, double z) {
  EXPECT_NEAR(got[0], x, 1e-3);
  EXPECT_NEAR(got[1], y, 1e-3);
  EXPECT_NEAR(got[2], z, 1e-3);
}

}  // namespace

TEST(VrchatTracker, KnownRotationsGiveUnityEulerAngles) {
  // Turning left (about our up axis, counterclockwise seen from above) is a negative yaw in
  // Unity, where positive y turns clockwise seen from above (left-handed).
  expect_euler(
      tracker(Eigen::Quaterniond(Eigen::AngleAxisd(30 * kDeg, Eigen::Vector3d::UnitZ()))).euler_deg,
      0, -30, 0);
  // About our +y (left) by +20 degrees: the nose goes down, a positive Unity pitch (about x).
  expect_euler(
      tracker(Eigen::Quaterniond(Eigen::AngleAxisd(20 * kDeg, Eigen::Vector3d::UnitY()))).euler_deg,
      20, 0, 0);
  // About our +x (forward) by +25 degrees: the left side goes up (rolling right), a negative
  // Unity roll about z (forward).
  expect_euler(
      tracker(Eigen::Quaterniond(Eigen::AngleAxisd(25 * kDeg, Eigen::Vector3d::UnitX()))).euler_deg,
      0, 0, -25);
  // Unity order: yaw 40 (ours -40 about z) after pitch 10 after roll 15, composed in our frame.
  const Eigen::Quaterniond ours = Eigen::AngleAxisd(-40 * kDeg, Eigen::Vector3d::UnitZ()) *
                                  Eigen::AngleAxisd(10 * kDeg, Eigen::Vector3d::UnitY()) *
                                  Eigen::AngleAxisd(-15 * kDeg, Eigen::Vector3d::UnitX());
  expect_euler(tracker(ours).euler_deg, 10, 40, 15);
  expect_euler(tracker(Eigen::Quaterniond::Identity()).euler_deg, 0, 0, 0);
}

TEST(VrchatTracker, EulerAnglesRebuildTheUnityRotation) {
  std::mt19937 rng(7);
  std::normal_distribution<double> n;
  for (int k = 0; k < 200; ++k) {
    const Eigen::Quaterniond q = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized();
    const auto e = unity_euler_deg({q.x(), q.y(), q.z(), q.w()});
    EXPECT_GE(e[0], -90.f);
    EXPECT_LE(e[0], 90.f);
    EXPECT_GT(e[1], -180.001f);
    EXPECT_LE(e[1], 180.001f);
    const Eigen::Quaterniond back = unity_from_euler(e);
    EXPECT_NEAR(std::abs(back.dot(q)), 1.0, 1e-6) << k;
  }
  // Gimbal lock (pitch +-90): the rotation is still rebuilt.
  const Eigen::Quaterniond lock = Eigen::AngleAxisd(30 * kDeg, Eigen::Vector3d::UnitY()) *
                                  Eigen::AngleAxisd(90 * kDeg, Eigen::Vector3d::UnitX()) *
                                  Eigen::AngleAxisd(20 * kDeg, Eigen::Vector3d::UnitZ());
  const auto e = unity_euler_deg({lock.x(), lock.y(), lock.z(), lock.w()});
  EXPECT_NEAR(std::abs(unity_from_euler(e).dot(lock)), 1.0, 1e-6);
}

TEST(VrchatTracker, PositionsInUnityAxesScaledByHeight) {
  const VrchatTracker t =
      tracker(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1.0, 2.0, 0.9), 1.1);
  EXPECT_NEAR(t.p[0], -2.2, 1e-6);  // x right = -our y (left)
  EXPECT_NEAR(t.p[1], 0.99, 1e-6);  // y up = our z
  EXPECT_NEAR(t.p[2], 1.1, 1e-6);   // z forward = our x
  PoseFrame f;
  reset_pose(f);
  f.p_earth_segment_m[0][1] = NAN;
  VrchatTracker bad;
  EXPECT_FALSE(vrchat_tracker_from_frame(f, 0, 1.0, bad));
}

namespace {

/// The known pose sent to oscdump: pelvis turned 90 degrees left at (0.5, -0.25, 0.95),
/// the left foot pitched 30 degrees down, the head rolled; every position distinct.
PoseFrame known_pose(int k) {
  PoseFrame f;
  reset_pose(f);
  for (int s = 0; s < kSegmentCount; ++s)
    f.p_earth_segment_m[s] = {0.01f * s, 0.02f * s, 0.1f + 0.05f * s};
  set_segment(f, Segment::pelvis,
              Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ())),
              {0.5, -0.25, 0.95});
  set_segment(f, Segment::foot_l,
              Eigen::Quaterniond(Eigen::AngleAxisd(30 * kDeg, Eigen::Vector3d::UnitY())),
              {0.1, 0.1, 0.08});
  set_segment(f, Segment::head,
              Eigen::Quaterniond(Eigen::AngleAxisd(-10 * kDeg, Eigen::Vector3d::UnitX())),
              {0.0, 0.0, 1.6});
  f.frame = static_cast<uint64_t>(k);
  f.t_ns = 1'000'000'000 + int64_t{k} * 20'000'000;
  return f;
}

}  // namespace

TEST(VrchatSender, RateLimitAndSlots) {
  const uint16_t port = static_cast<uint16_t>(test::free_loopback_port(SOCK_DGRAM));
  VrchatSender s;
  VrchatSender::Options opt;
  opt.port = port;
  opt.slots = {index(Segment::pelvis), -1, -1, -1, -1, -1, -1, index(Segment::foot_r)};
  std::string err;
  ASSERT_TRUE(s.open(opt, &err)) << err;
  PoseFrame f;
  reset_pose(f);
  for (int k = 0; k < 20; ++k) {
    f.t_ns = int64_t{k} * 4'000'000;
    s.publish(f);
  }
  EXPECT_EQ(s.stats().frames_sent, 7u);
  EXPECT_EQ(s.stats().frames_rate_limited, 13u);
  EXPECT_EQ(s.stats().messages_sent, 7u * 6u);  // 2 slots + head, position and rotation
  opt.host = "not-an-ip";
  EXPECT_FALSE(s.open(opt, &err));
  EXPECT_NE(err.find("not-an-ip"), std::string::npos);
}

TEST(VrchatSender, OscdumpReceivesTrackersWithUnityPositionsAndEulerAngles) {
  if (!test::have_oscdump()) GTEST_SKIP() << "oscdump (liblo-tools) missing";
  const uint16_t port = static_cast<uint16_t>(test::free_loopback_port(SOCK_DGRAM));
  VrchatSender s;
  VrchatSender::Options opt;
  opt.port = port;
  opt.scale = 1.0;
  std::string err;
  ASSERT_TRUE(s.open(opt, &err)) << err;
  const test::OscdumpCapture cap =
      test::capture_oscdump(port, [&](int k) { s.publish(known_pose(k)); });
  const std::string& text = cap.text;
  ASSERT_GT(cap.frames_before_first_output, 0) << "oscdump printed nothing";

  // Expected values per address.
  const PoseFrame f = known_pose(0);
  std::map<std::string, std::array<float, 3>> expect;
  const char* slot_names[] = {"1", "2", "3", "4", "5", "6", "7", "8"};
  for (int i = 0; i < outputs::kVrchatTrackerSlots; ++i) {
    VrchatTracker t;
    ASSERT_TRUE(vrchat_tracker_from_frame(f, opt.slots[i], 1.0, t));
    expect[std::string("/tracking/trackers/") + slot_names[i] + "/position"] = t.p;
    expect[std::string("/tracking/trackers/") + slot_names[i] + "/rotation"] = t.euler_deg;
  }
  // Known values: tracker 1 (the pelvis), tracker 3 (the left foot), the head.
  expect_euler(expect["/tracking/trackers/1/rotation"], 0, -90, 0);
  EXPECT_NEAR(expect["/tracking/trackers/1/position"][0], 0.25, 1e-6);
  EXPECT_NEAR(expect["/tracking/trackers/1/position"][1], 0.95, 1e-6);
  EXPECT_NEAR(expect["/tracking/trackers/1/position"][2], 0.5, 1e-6);
  expect_euler(expect["/tracking/trackers/3/rotation"], 30, 0, 0);
  expect["/tracking/trackers/head/position"] = {0.f, 1.6f, 0.f};
  expect["/tracking/trackers/head/rotation"] = {0.f, 0.f, 10.f};

  // oscdump lines: "<timetag> <address> <types> args...".
  std::istringstream in(text);
  std::string line;
  std::map<std::string, int> seen;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string tt, address, types;
    ls >> tt >> address >> types;
    ASSERT_TRUE(expect.count(address)) << line;
    ASSERT_EQ(types, "fff") << line;
    float v[3];
    ls >> v[0] >> v[1] >> v[2];
    ASSERT_FALSE(ls.fail()) << line;
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(v[c], expect[address][c], 2e-5) << line;
    ++seen[address];
  }
  EXPECT_EQ(seen.size(), expect.size()) << text.substr(0, 2000);  // all 18 addresses
  for (const auto& [address, count] : seen)
    EXPECT_GE(count, 3) << address;
}
