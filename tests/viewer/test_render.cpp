// The real viewer program, rendering under Xvfb + Mesa: known poses published through a real
// shared posture must appear where the camera projects them, move when the person moves, and
// show their flags; the HUD shows text and the recording indicator.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>

#include "mocap/outputs/posture_shm.hpp"
#include "mocap/session/session_writer.hpp"
#include "mocap/skeleton/bvh.hpp"
#include "mocap/viewer/avatar_geometry.hpp"
#include "mocap/viewer/camera.hpp"
#include "mocap/viewer/png_io.hpp"
#include "mocap/viewer/session_source.hpp"
#include "mocap/viewer/synthetic_source.hpp"

namespace mocap::viewer {
namespace {

constexpr int kW = 480, kH = 360;

/// Runs mocap-viewer with `args` (`env`: what `env` should change first); returns its exit
/// status.
int run_viewer(const std::string& args, const std::string& env = "") {
  // Under ASan: GLFW dlcloses libGL at exit, so the GL driver's own leaks are reported from an
  // "<unknown module>" that tests/lsan.supp cannot name; leak checking stays on for the
  // viewer's code in test_viewer_core.
  const std::string err = "/tmp/mocap-viewer-render-" + std::to_string(getpid()) + ".err";
  const std::string cmd = "env " + env + " ASAN_OPTIONS=\"${ASAN_OPTIONS}:detect_leaks=0\" " +
                          std::string(MOCAP_VIEWER_EXE) + " " + args + " 2>" + err;
  const int rc = std::system(cmd.c_str());
  // A failed run says why in the test's output (the viewer's own message).
  std::ifstream in(err);
  const std::string said((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (rc != 0) std::fprintf(stderr, "mocap-viewer %s: rc %d: %s\n", args.c_str(), rc, said.c_str());
  std::remove(err.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

class Render : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::getenv("DISPLAY")) GTEST_SKIP() << "needs a display: run under xvfb-run";
    shm_ = "/mocap-viewer-render-" + std::to_string(getpid());
    png_ = "/tmp/mocap-viewer-render-" + std::to_string(getpid()) + ".png";
    writer_ = std::make_unique<outputs::PostureWriter>(shm_);
  }
  void TearDown() override { std::remove(png_.c_str()); }

  /// Renders the published pose without HUD, labels, earth axes or shadows.
  RgbImage render_published(const PoseFrame& f, const std::string& extra = "") {
    writer_->publish(f);
    const std::string size = std::to_string(kW) + "x" + std::to_string(kH);
    EXPECT_EQ(run_viewer("--shm " + shm_ + " --screenshot " + png_ + " --frames 2 --size " + size +
                         " --no-hud --no-labels --no-earth-axes --no-shadows " + extra),
              0);
    return read_png(png_);
  }

  std::string shm_, png_;
  std::unique_ptr<outputs::PostureWriter> writer_;
  BodyDimensions dims_ = body_dimensions_from_height(1.75);
  OrbitCamera camera_ = OrbitCamera::framing(1);
};

/// Avatar colours are saturated; floor and background are nearly grey.
bool is_body(const uint8_t* p) {
  const int hi = std::max({p[0], p[1], p[2]}), lo = std::min({p[0], p[1], p[2]});
  return hi - lo > 28;
}

struct Blob {
  int count = 0;
  Eigen::Vector2f centroid = Eigen::Vector2f::Zero();
};
Blob body_blob(const RgbImage& img) {
  Blob b;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      if (is_body(img.at(x, y))) {
        ++b.count;
        b.centroid += Eigen::Vector2f(x, y);
      }
  if (b.count) b.centroid /= static_cast<float>(b.count);
  return b;
}

Eigen::Vector2f projected(const OrbitCamera& c, const PoseFrame& f, const BodyDimensions& d,
                          Segment s) {
  return *c.project(segment_midpoint(f, d, index(s)), kW, kH);
}

const uint8_t* pixel(const RgbImage& img, const Eigen::Vector2f& p) {
  return img.at(static_cast<int>(p.x()), static_cast<int>(p.y()));
}

TEST_F(Render, AvatarAppearsWhereTheCameraProjectsIt) {
  PoseFrame f = reference_pose(dims_, Eigen::Vector3f::Zero());
  f.flags = kFrameCalibrated;
  const RgbImage img = render_published(f);
  ASSERT_EQ(img.width, kW);
  for (Segment s : {Segment::head, Segment::torso, Segment::pelvis, Segment::thigh_l,
                    Segment::shank_r, Segment::upper_arm_l, Segment::forearm_r}) {
    const Eigen::Vector2f p = projected(camera_, f, dims_, s);
    EXPECT_TRUE(is_body(pixel(img, p))) << name(s) << " at " << p.transpose();
  }
  // Background above the head, floor beside the feet, corners: no body.
  EXPECT_FALSE(is_body(img.at(kW / 2, 5)));
  EXPECT_FALSE(is_body(pixel(img, *camera_.project(Eigen::Vector3f(0, 1.2f, 0), kW, kH))));
  EXPECT_FALSE(is_body(img.at(2, kH - 3)));
  const Blob b = body_blob(img);
  EXPECT_GT(b.count, kW * kH / 200);
  EXPECT_LT(b.count, kW * kH / 5);
  const Eigen::Vector2f centre = projected(camera_, f, dims_, Segment::pelvis);
  EXPECT_LT((b.centroid - centre).norm(), 0.1f * kW) << b.centroid.transpose();
}

TEST_F(Render, BlobMovesWithTheAvatar) {
  PoseFrame here = reference_pose(dims_, Eigen::Vector3f::Zero());
  PoseFrame there = reference_pose(dims_, Eigen::Vector3f(-0.3f, 0.9f, 0));
  here.flags = there.flags = kFrameCalibrated;
  const Blob a = body_blob(render_published(here));
  const Blob b = body_blob(render_published(there));
  const Eigen::Vector2f expected = projected(camera_, there, dims_, Segment::pelvis) -
                                   projected(camera_, here, dims_, Segment::pelvis);
  const Eigen::Vector2f moved = b.centroid - a.centroid;
  ASSERT_GT(expected.norm(), 40.0f);
  EXPECT_LT((moved - expected).norm(), 0.25f * expected.norm())
      << "moved " << moved.transpose() << " expected " << expected.transpose();
}

TEST_F(Render, FlaggedSegmentIsTintedRed) {
  PoseFrame f = reference_pose(dims_, Eigen::Vector3f::Zero());
  f.flags = kFrameCalibrated;
  const Eigen::Vector2f thigh = projected(camera_, f, dims_, Segment::thigh_l);
  const RgbImage plain = render_published(f);
  f.segment_flags[index(Segment::thigh_l)] = kSegTracked | kSegLimitViolated;
  const RgbImage flagged = render_published(f);
  const uint8_t* p = pixel(plain, thigh);
  const uint8_t* q = pixel(flagged, thigh);
  EXPECT_GT(p[2], p[0]) << "left thigh is blue normally";
  EXPECT_GT(q[0], q[1] + 60) << "limit violation is red";
  EXPECT_GT(q[0], q[2] + 60);
  // The other thigh keeps its colour.
  const Eigen::Vector2f other = projected(camera_, f, dims_, Segment::thigh_r);
  EXPECT_EQ(pixel(plain, other)[0], pixel(flagged, other)[0]);
}

TEST_F(Render, StickFigureIsThinnerThanSolid) {
  PoseFrame f = reference_pose(dims_, Eigen::Vector3f::Zero());
  f.flags = kFrameCalibrated;
  const Blob solid = body_blob(render_published(f));
  const Blob stick = body_blob(render_published(f, "--stick"));
  EXPECT_GT(stick.count, 0);
  EXPECT_LT(stick.count * 2, solid.count);
}

TEST_F(Render, HudShowsTextAndRecordingIndicator) {
  PoseFrame f = reference_pose(dims_, Eigen::Vector3f::Zero());
  f.flags = kFrameCalibrated | kFrameRecording;
  writer_->publish(f);
  auto count = [](const RgbImage& img, int x0, int y0, int x1, int y1, auto pred) {
    int n = 0;
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x)
        n += pred(img.at(x, y)) ? 1 : 0;
    return n;
  };
  auto white = [](const uint8_t* p) { return p[0] > 200 && p[1] > 200 && p[2] > 200; };
  auto red = [](const uint8_t* p) { return p[0] > 180 && p[1] < 90 && p[2] < 90; };
  const std::string args = "--shm " + shm_ + " --screenshot " + png_ + " --frames 2 --size 960x540";
  ASSERT_EQ(run_viewer(args), 0);
  const RgbImage with = read_png(png_);
  ASSERT_EQ(run_viewer(args + " --no-hud"), 0);
  const RgbImage without = read_png(png_);
  EXPECT_GT(count(with, 0, 0, 400, 40, white), 100) << "title and frame rate";
  EXPECT_EQ(count(without, 0, 0, 400, 40, white), 0);
  EXPECT_GT(count(with, 800, 0, 960, 40, red), 100) << "REC indicator";
  EXPECT_EQ(count(without, 800, 0, 960, 40, red), 0);
}

TEST_F(Render, HudFitsASmallWindowWithALongSensorName) {
  PoseFrame f = reference_pose(dims_, Eigen::Vector3f::Zero());
  f.flags = kFrameCalibrated;
  f.sensor_count = 3;
  const char* names[] = {"pelvis", "capteur_avant_bras_gau", "foot_r"};
  for (int i = 0; i < 3; ++i) {
    std::snprintf(f.sensors[i].name, sizeof f.sensors[i].name, "%s", names[i]);
    f.sensors[i].segment = static_cast<int8_t>(i);
    f.sensors[i].state = 2;  // streaming: the table's green
    f.sensors[i].rate_hz = 100;
  }
  writer_->publish(f);
  const int w = 320, h = 240;
  const std::string args = "--shm " + shm_ + " --screenshot " + png_ +
                           " --frames 2 --no-labels --size " + std::to_string(w) + "x" +
                           std::to_string(h);
  ASSERT_EQ(run_viewer(args), 0);
  const RgbImage hud = read_png(png_);
  ASSERT_EQ(run_viewer(args + " --no-hud"), 0);
  const RgbImage plain = read_png(png_);
  auto green = [](const uint8_t* p) { return p[1] > 170 && p[0] < 130 && p[2] < 140; };
  int table = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      table += green(hud.at(x, y)) ? 1 : 0;
  EXPECT_GT(table, 50) << "the sensor table is drawn";
  // Text and panels stay left of the 12 px right margin: there the image is the scene alone.
  int touched = 0;
  for (int y = 0; y < h; ++y)
    for (int x = w - 12; x < w; ++x)
      touched += std::memcmp(hud.at(x, y), plain.at(x, y), 3) != 0 ? 1 : 0;
  EXPECT_EQ(touched, 0) << "HUD pixels in the right margin";
}

TEST_F(Render, SyntheticCrowdStandsOnItsGrid) {
  const int n = 16, frames = 3;
  ASSERT_EQ(run_viewer("--source synthetic --avatars 16 --screenshot " + png_ +
                       " --frames 3 --size " + std::to_string(kW) + "x" + std::to_string(kH) +
                       " --no-hud --no-labels --no-earth-axes --no-shadows"),
            0);
  const RgbImage img = read_png(png_);
  const OrbitCamera cam = OrbitCamera::framing(n);
  SyntheticSource src(n, dims_);
  PoseFrame f;
  for (int i = 0; i < n; ++i) {
    src.pose_at(i, (frames - 1) / 60.0, f);
    const auto p = cam.project(segment_midpoint(f, dims_, index(Segment::torso)), kW, kH);
    ASSERT_TRUE(p);
    EXPECT_TRUE(is_body(pixel(img, *p))) << "avatar " << i << " at " << p->transpose();
  }
}

TEST_F(Render, BvhPlaybackShowsTheFilesPose) {
  // A clip written by the skeleton's BvhWriter: standing 2 m east of the origin with the left
  // thigh raised forward to horizontal.
  const std::string bvh = png_ + ".bvh";
  {
    BvhWriter w(bvh, BodyModel(dims_));
    std::array<Eigen::Quaternionf, kSegmentCount> q;
    q.fill(Eigen::Quaternionf::Identity());
    q[index(Segment::thigh_l)] = Eigen::AngleAxisf(-1.5707963f, Eigen::Vector3f::UnitY());
    PoseFrame f;
    reset_pose(f);
    for (int k = 0; k < 10; ++k) {
      pose_from_joint_rotations(dims_, q, Eigen::Vector3f(2, 0, 0.93f), f);
      w.write_frame(f);
    }
  }
  ASSERT_EQ(run_viewer("--play " + bvh + " --screenshot " + png_ + " --frames 3 --size " +
                       std::to_string(kW) + "x" + std::to_string(kH) +
                       " --no-hud --no-labels --no-earth-axes --no-shadows"),
            0);
  const RgbImage img = read_png(png_);
  const BvhMotion motion(load_bvh(bvh));
  PoseFrame f;
  motion.to_pose_frame(2, f);
  std::remove(bvh.c_str());
  OrbitCamera cam = OrbitCamera::framing(1);  // --play follows the pelvis
  cam.target_m.x() = f.p_earth_segment_m[0][0];
  cam.target_m.y() = f.p_earth_segment_m[0][1];
  EXPECT_NEAR(cam.target_m.x(), 2.0f, 0.01f);
  for (Segment s : {Segment::head, Segment::torso, Segment::thigh_l, Segment::shank_r}) {
    const auto p = cam.project(segment_midpoint(f, motion.dimensions(), index(s)), kW, kH);
    ASSERT_TRUE(p);
    EXPECT_TRUE(is_body(pixel(img, *p))) << name(s) << " at " << p->transpose();
  }
  // The raised thigh points forward (+x, towards the camera's side), not down.
  const Eigen::Vector3f knee(f.p_earth_segment_m[index(Segment::shank_l)][0],
                             f.p_earth_segment_m[index(Segment::shank_l)][1],
                             f.p_earth_segment_m[index(Segment::shank_l)][2]);
  EXPECT_GT(knee.x(), 2.3f);
  EXPECT_GT(knee.z(), 0.8f);
}

TEST_F(Render, SessionPlaybackShowsTheRecordedPose) {
  // A session as mocapd records it: a 1.60 m person crouching on the left leg 1 m north.
  const std::string path = png_ + ".mocap";
  const BodyDimensions dims = body_dimensions_from_height(1.60);
  PoseFrame f;
  reset_pose(f);
  std::array<Eigen::Quaternionf, kSegmentCount> q;
  q.fill(Eigen::Quaternionf::Identity());
  q[index(Segment::thigh_l)] = Eigen::AngleAxisf(-1.2f, Eigen::Vector3f::UnitY());
  q[index(Segment::shank_l)] = Eigen::AngleAxisf(1.2f, Eigen::Vector3f::UnitY());
  pose_from_joint_rotations(dims, q, Eigen::Vector3f(0, 1, 0.8f), f);
  {
    std::string error;
    auto w = SessionWriter::create(path, session::SessionHeader{}, {}, &error);
    ASSERT_TRUE(w) << error;
    for (int k = 0; k < 30; ++k) {
      f.frame = static_cast<uint64_t>(k);
      f.t_ns = int64_t{k} * 8'333'333;
      ASSERT_TRUE(w->append_pose(f));
    }
    ASSERT_TRUE(w->close());
  }
  ASSERT_EQ(run_viewer("--play " + path + " --screenshot " + png_ + " --frames 3 --size " +
                       std::to_string(kW) + "x" + std::to_string(kH) +
                       " --no-hud --no-labels --no-earth-axes --no-shadows"),
            0);
  std::remove(path.c_str());
  const RgbImage img = read_png(png_);
  OrbitCamera cam = OrbitCamera::framing(1);  // --play follows the pelvis
  cam.target_m.x() = f.p_earth_segment_m[0][0];
  cam.target_m.y() = f.p_earth_segment_m[0][1];
  for (Segment s :
       {Segment::head, Segment::torso, Segment::thigh_l, Segment::shank_l, Segment::shank_r}) {
    const auto p = cam.project(segment_midpoint(f, dims, index(s)), kW, kH);
    ASSERT_TRUE(p);
    EXPECT_TRUE(is_body(pixel(img, *p))) << name(s) << " at " << p->transpose();
  }
  // Somewhere the body is not: where the left shank would hang in a standing pose.
  PoseFrame standing = f;
  q.fill(Eigen::Quaternionf::Identity());
  pose_from_joint_rotations(dims, q, Eigen::Vector3f(0, 1, 0.8f), standing);
  const auto hanging =
      cam.project(segment_midpoint(standing, dims, index(Segment::foot_l)), kW, kH);
  ASSERT_TRUE(hanging);
  EXPECT_FALSE(is_body(pixel(img, *hanging))) << "left foot drawn where a standing pose has it";
}

TEST_F(Render, MissingDaemonAndBadOptionsAreReported) {
  EXPECT_EQ(
      run_viewer("--shm /mocap-viewer-nobody-here --wait 0.3 --screenshot " + png_ + " --frames 1"),
      3);
  EXPECT_EQ(run_viewer("--connect localhost --screenshot " + png_), 1) << "no port";
  EXPECT_EQ(run_viewer("--avatars 0 --screenshot " + png_), 2);
  EXPECT_EQ(run_viewer("--size 12xfoo --screenshot " + png_), 2);
  EXPECT_EQ(run_viewer("--play /nonexistent.bvh --screenshot " + png_), 1);
  EXPECT_EQ(run_viewer("--play /nonexistent.session --screenshot " + png_), 1);
}

// --screenshot without any display server: EGL on Mesa's surfaceless platform.
TEST(RenderWithoutDisplay, ScreenshotNeedsNoXServer) {
  const std::string png = "/tmp/mocap-viewer-nodisplay-" + std::to_string(getpid()) + ".png";
  ASSERT_EQ(run_viewer("--source synthetic --frames 2 --size 200x150 --screenshot " + png,
                       "-u DISPLAY -u WAYLAND_DISPLAY"),
            0);
  const RgbImage img = read_png(png);
  EXPECT_EQ(img.width, 200);
  EXPECT_EQ(img.height, 150);
  int body = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      body += is_body(img.at(x, y)) ? 1 : 0;
  EXPECT_GT(body, 20) << "the avatar is drawn";
  std::remove(png.c_str());
}

}  // namespace
}  // namespace mocap::viewer
