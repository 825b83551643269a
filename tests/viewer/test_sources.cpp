// Pose sources: forward kinematics, the synthetic performer, and the shared-posture source
// against a real PostureWriter.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>

#include "mocap/outputs/posture_shm.hpp"
#include "mocap/viewer/avatar_geometry.hpp"
#include "mocap/viewer/camera.hpp"
#include "mocap/viewer/shm_source.hpp"
#include "mocap/viewer/synthetic_source.hpp"

namespace mocap::viewer {
namespace {

Eigen::Vector3f p_of(const PoseFrame& f, int s) {
  return {f.p_earth_segment_m[s][0], f.p_earth_segment_m[s][1], f.p_earth_segment_m[s][2]};
}

TEST(ForwardKinematics, ThighRaisedForwardPutsTheKneeInFront) {
  const BodyDimensions dims = body_dimensions_from_height(1.8);
  std::array<Eigen::Quaternionf, kSegmentCount> q;
  q.fill(Eigen::Quaternionf::Identity());
  q[index(Segment::thigh_r)] = Eigen::AngleAxisf(-1.5707963f, Eigen::Vector3f::UnitY());
  PoseFrame f;
  reset_pose(f);
  pose_from_joint_rotations(dims, q, Eigen::Vector3f(0, 0, 1), f);
  const Eigen::Vector3f hip = p_of(f, index(Segment::thigh_r)),
                        knee = p_of(f, index(Segment::shank_r));
  EXPECT_NEAR(knee.x() - hip.x(), 0.245 * 1.8, 1e-4);
  EXPECT_NEAR(knee.z(), hip.z(), 1e-4);
  EXPECT_LT(hip.y(), 0) << "right hip on the -y side";
  // The shank's own frame turned with the thigh: its earth quaternion equals the thigh's.
  EXPECT_NEAR(f.q_earth_segment[index(Segment::shank_r)][2],
              f.q_earth_segment[index(Segment::thigh_r)][2], 1e-6);
}

TEST(SyntheticSource, PosesAreFiniteKeepBoneLengthsAndStandOnTheFloor) {
  const BodyDimensions dims = body_dimensions_from_height(1.75);
  SyntheticSource src(9, dims);
  std::vector<PoseFrame> frames;
  for (double t = 0; t < 7; t += 0.173) {
    ASSERT_TRUE(src.poll(t, frames));
    ASSERT_EQ(frames.size(), 9u);
    for (size_t a = 0; a < frames.size(); ++a) {
      const PoseFrame& f = frames[a];
      ASSERT_TRUE(pose_is_finite(f));
      for (int s = 1; s < kSegmentCount; ++s) {
        const float bone = (p_of(f, s) - p_of(f, kSegmentParent[s])).norm();
        EXPECT_NEAR(bone, dims.joint_offset_m[s].norm(), 1e-4) << kSegmentNames[s];
      }
      const Eigen::Vector3f pelvis = p_of(f, 0), home = crowd_origin(static_cast<int>(a), 9);
      EXPECT_LT((pelvis.head<2>() - home.head<2>()).norm(), 0.2f);
      EXPECT_GT(p_of(f, index(Segment::foot_l)).z(), 0.0f);
      EXPECT_LT(std::min(p_of(f, index(Segment::foot_l)).z(), p_of(f, index(Segment::foot_r)).z()),
                0.2f);
    }
  }
}

TEST(SyntheticSource, FirstAvatarShowsEveryFlagOnSchedule) {
  const BodyDimensions dims = body_dimensions_from_height(1.75);
  SyntheticSource src(2, dims);
  PoseFrame f;
  src.pose_at(0, 1.0, f);
  EXPECT_TRUE(f.segment_flags[index(Segment::forearm_l)] & kSegLimitViolated);
  EXPECT_GT(f.joint_violation_deg[index(Segment::forearm_l)], 0);
  src.pose_at(0, 3.0, f);
  EXPECT_TRUE(f.segment_flags[index(Segment::shank_r)] & kSegStale);
  bool stale_sensor = false;
  for (uint32_t i = 0; i < f.sensor_count; ++i)
    stale_sensor |= f.sensors[i].state == 3;
  EXPECT_TRUE(stale_sensor);
  src.pose_at(0, 5.0, f);
  EXPECT_TRUE(f.segment_flags[index(Segment::upper_arm_r)] & kSegMagDisturbed);
  src.pose_at(1, 1.0, f);
  for (uint32_t flags : f.segment_flags)
    EXPECT_EQ(flags, kSegTracked);
}

TEST(SyntheticSource, PauseFreezesAndSeekMoves) {
  SyntheticSource src(1, body_dimensions_from_height(1.75));
  std::vector<PoseFrame> a, b;
  src.poll(1.0, a);
  src.set_paused(true);
  src.poll(2.5, b);
  EXPECT_EQ(a[0].p_earth_segment_m, b[0].p_earth_segment_m);
  src.set_paused(false);
  src.seek_by(0.3);
  src.poll(2.6, b);
  EXPECT_NE(a[0].p_earth_segment_m, b[0].p_earth_segment_m);
}

TEST(ShmSource, WaitsForTheDaemonThenShowsItsNewestFrame) {
  const std::string name = "/mocap-viewer-test-" + std::to_string(getpid());
  ShmSource src(name);
  std::vector<PoseFrame> frames;
  EXPECT_FALSE(src.poll(0.0, frames));
  EXPECT_NE(src.status().find("WAITING"), std::string::npos);

  auto writer = std::make_unique<outputs::PostureWriter>(name);
  PoseFrame f = reference_pose(body_dimensions_from_height(1.7), Eigen::Vector3f(1, 2, 0));
  f.frame = 7;
  writer->publish(f);
  EXPECT_FALSE(src.poll(0.1, frames)) << "retries at most twice a second";
  ASSERT_TRUE(src.poll(0.6, frames));
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].frame, 7u);
  EXPECT_FLOAT_EQ(frames[0].p_earth_segment_m[0][0], 1.0f);
  EXPECT_FALSE(src.poll(0.7, frames)) << "nothing new published";
  f.frame = 8;
  writer->publish(f);
  ASSERT_TRUE(src.poll(0.8, frames));
  EXPECT_EQ(frames[0].frame, 8u);
  EXPECT_NE(src.status().find(name), std::string::npos);

  // The daemon restarts: a new segment under the same name. The viewer maps it again.
  writer.reset();
  auto restarted = std::make_unique<outputs::PostureWriter>(name);
  f.frame = 100;
  restarted->publish(f);
  double t = 0.9;
  for (; t < 5 && (frames[0].frame != 100); t += 0.1)
    src.poll(t, frames);
  EXPECT_EQ(frames[0].frame, 100u) << "still showing the old daemon's frame";
  EXPECT_LT(t, 4.0);
}

}  // namespace
}  // namespace mocap::viewer
