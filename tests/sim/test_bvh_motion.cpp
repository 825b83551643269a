// BVH files as performer motion: a walk written with the skeleton's BvhWriter and read back
// through make_bvh_motion reproduces the original segment orientations and root path.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "mocap/core/units.hpp"
#include "mocap/sim/performer.hpp"
#include "mocap/skeleton/bvh.hpp"

namespace mocap::sim {
namespace {

std::string temp_bvh(const char* stem) {
  return (std::filesystem::temp_directory_path() /
          (std::string(stem) + std::to_string(getpid()) + ".bvh"))
      .string();
}

/// Writes 8 s of `original` from 4 s on (the walk itself) as a 60 Hz BVH file.
void write_bvh(const std::string& path, const Performer& original) {
  BvhWriter w(path, BodyModel(original.dims()), {1.0 / 60, 100.0});
  TruthFrame t;
  for (int k = 0; k * (1.0 / 60) <= 8.0; ++k) {
    original.truth_at(4.0 + k / 60.0, t);
    w.write_frame(to_pose_frame(t));
  }
}

/// Largest segment orientation (deg) and root position (m) difference between a and b over
/// [from_s, to_s) of a, with b shifted by b_minus_a_s.
std::pair<double, double> worst_difference(const Performer& a, const Performer& b, double from_s,
                                           double to_s, double b_minus_a_s) {
  TruthFrame fa, fb;
  double worst_deg = 0, worst_m = 0;
  for (double t = from_s; t < to_s; t += 0.25) {
    a.truth_at(t, fa);
    b.truth_at(t + b_minus_a_s, fb);
    for (int s = 0; s < kSegmentCount; ++s)
      worst_deg = std::max(
          worst_deg, fa.q_earth_segment[s].angularDistance(fb.q_earth_segment[s]) * kDegPerRad);
    worst_m = std::max(worst_m, (fa.p_earth_segment_m[0] - fb.p_earth_segment_m[0]).norm());
  }
  return {worst_deg, worst_m};
}

TEST(BvhMotion, WalkRoundTripsThroughABvhFile) {
  const std::string path = temp_bvh("mocap_sim_walk_");
  PerformerParams p;
  p.motion = "walk";
  p.loop = false;
  Performer original(p);
  write_bvh(path, original);
  auto motion = std::shared_ptr<const Motion>(make_bvh_motion(path, 3.0, 1.0));
  std::filesystem::remove(path);
  EXPECT_NEAR(motion->duration_s(), 3.0 + 1.0 + 8.0, 1.0 / 60 + 1e-9);
  EXPECT_EQ(motion->calibration_window_s().second, 3.0);
  Performer replay(p, motion);
  const auto [worst_deg, worst_m] = worst_difference(original, replay, 4.5, 11.5, 0.0);
  EXPECT_LT(worst_deg, 1.0);  // lead-in 3 s + blend 1 s: the clip from 4 s as in the original
  EXPECT_LT(worst_m, 0.02);
  // The virtual sensors ride on it and the stream stays finite.
  std::vector<ImuSample> out;
  replay.step_to(6'000'000'000, out);
  ASSERT_GT(out.size(), 15u * 500);
  for (const auto& s : out)
    ASSERT_TRUE(s.acc_m_s2.allFinite() && s.gyr_rad_s.allFinite());
}

// "calibrate+FILE.bvh": the calibration procedure (N-pose stand, knee bends with elbow curls)
// with the feet planted where the clip starts, then the clip; "FILE.bvh" by name is the file.
TEST(BvhMotion, CalibrationProcedureBeforeAFileByName) {
  const std::string path = temp_bvh("mocap_sim_calib_walk_");
  PerformerParams p;
  p.motion = "walk";
  p.loop = false;
  const Performer original(p);
  write_bvh(path, original);
  PerformerParams bp = p;
  bp.motion = path;
  const Performer plain(bp);
  bp.motion = "calibrate+" + path;
  const Performer calibrated(bp);
  std::filesystem::remove(path);
  const double prelude_s = 3.0 + calibration_moves_s();
  EXPECT_NEAR(plain.track().period_s(), 3.0 + 1.0 + 8.0, 1.0 / 60 + 1e-9);
  EXPECT_NEAR(calibrated.track().period_s(), prelude_s + 1.0 + 8.0, 1.0 / 60 + 1e-9);
  EXPECT_EQ(calibrated.calibration_window_s(), std::make_pair(0.0, 3.0));
  // During the procedure the ankles stay where the N-pose put them, the knees bend, and the
  // body faces the clip's first heading.
  TruthFrame start, f;
  calibrated.truth_at(0.0, start);
  original.truth_at(4.0, f);
  const auto yaw = [](const Eigen::Quaterniond& q) {
    const Eigen::Vector3d x = q * Eigen::Vector3d::UnitX();
    return std::atan2(x.y(), x.x());
  };
  EXPECT_NEAR(yaw(start.q_earth_segment[0]), yaw(f.q_earth_segment[0]), 0.1);
  double max_ankle_shift_m = 0, max_knee_deg = 0;
  for (double t = 0; t <= prelude_s; t += 0.05) {
    calibrated.truth_at(t, f);
    for (Segment foot : {Segment::foot_l, Segment::foot_r})
      max_ankle_shift_m = std::max(
          max_ankle_shift_m,
          (f.p_earth_segment_m[index(foot)] - start.p_earth_segment_m[index(foot)]).norm());
    max_knee_deg =
        std::max(max_knee_deg, f.q_parent_segment[index(Segment::shank_l)].angularDistance(
                                   Eigen::Quaterniond::Identity()) *
                                   kDegPerRad);
  }
  EXPECT_LT(max_ankle_shift_m, 1e-6);
  EXPECT_GT(max_knee_deg, 40.0);
  // Then the clip, as the plain file plays it (shifted by the procedure minus the lead-in).
  const auto [worst_deg, worst_m] = worst_difference(plain, calibrated, 4.5, 11.5, prelude_s - 3.0);
  EXPECT_LT(worst_deg, 1e-6);
  EXPECT_LT(worst_m, 1e-6);
}

// "session<S>+FILE.bvh": the clip played back and forth for at least S seconds (a long
// session). No segment ever turns faster than in the clip played once (the turning points ease
// through zero speed: no step in any rate, which the virtual gyros would see as a spike), each
// pass retraces the clip, and two passes bring the performer back where the first began.
TEST(BvhMotion, ASessionPlaysTheClipBackAndForthWithoutASnap) {
  const std::string path = temp_bvh("mocap_sim_session_walk_");
  PerformerParams p;
  p.motion = "walk";
  p.loop = false;
  write_bvh(path, Performer(p));
  const auto once = std::shared_ptr<const Motion>(make_bvh_motion(path, 3.0, 1.0));
  const auto session =
      std::shared_ptr<const Motion>(make_motion("session30+" + path));  // a 8 s clip: 4 passes
  std::filesystem::remove(path);
  const double clip_s = once->duration_s() - 4.0;
  EXPECT_NEAR(session->duration_s(), 4.0 + 4 * clip_s, 1e-9);
  EXPECT_EQ(session->calibration_window_s(), once->calibration_window_s());
  const auto largest_step_deg = [](const Motion& m, double from_s, double to_s) {
    BodyPose a, b;
    TruthFrame fa, fb;
    const BodyDimensions dims = *m.dimensions();
    double worst = 0;
    m.pose(from_s, a);
    truth_forward_kinematics(dims, a, fa);
    for (double t = from_s + 0.002; t <= to_s; t += 0.002) {
      m.pose(t, b);
      truth_forward_kinematics(dims, b, fb);
      for (int s = 0; s < kSegmentCount; ++s)
        worst = std::max(worst, fa.q_earth_segment[s].angularDistance(fb.q_earth_segment[s]));
      fa = fb;
    }
    return worst * kDegPerRad;
  };
  const double once_deg = largest_step_deg(*once, 4.0, once->duration_s());
  EXPECT_GT(once_deg, 0.1);
  EXPECT_LE(largest_step_deg(*session, 3.0, session->duration_s()), once_deg * 1.01);
  // Into the clip from the lead-in, and around the first turning point, at a rate the clip has.
  EXPECT_LE(largest_step_deg(*session, 3.0, 5.0), once_deg * 1.01);
  // The second pass retraces the first backward; after two passes it is back at the start.
  BodyPose a, b;
  for (double u : {1.0, 3.0, 5.0}) {
    session->pose(4.0 + u, a);
    session->pose(4.0 + 2 * clip_s - u, b);
    EXPECT_LT(a.q_earth_pelvis.angularDistance(b.q_earth_pelvis) * kDegPerRad, 1e-6) << u;
    EXPECT_LT((a.p_earth_pelvis_m - b.p_earth_pelvis_m).norm(), 1e-9) << u;
  }
  session->pose(4.0, a);
  session->pose(4.0 + 2 * clip_s, b);
  EXPECT_LT((a.p_earth_pelvis_m - b.p_earth_pelvis_m).norm(), 1e-9);
  EXPECT_THROW(make_motion("session30+walk"), std::invalid_argument);
  EXPECT_THROW(make_motion("session+" + path), std::invalid_argument);
  EXPECT_THROW(make_motion("session-5+" + path), std::invalid_argument);
  // A file whose name begins with "session" is a file (here one that does not exist).
  EXPECT_THROW(make_motion("session_take.bvh"), std::runtime_error);
}

TEST(BvhMotion, MissingFileIsAnError) {
  EXPECT_THROW(make_bvh_motion("/nonexistent/walk.bvh"), std::runtime_error);
  EXPECT_THROW(make_motion("calibrate+/nonexistent/walk.BVH"), std::runtime_error);
  try {
    make_motion("walk.bvx");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("ending in .bvh"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace mocap::sim
