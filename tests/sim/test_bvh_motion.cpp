// BVH files as performer motion: a walk written with the skeleton's BvhWriter and read back
// through make_bvh_motion reproduces the original segment orientations and root path.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>

#include "mocap/sim/performer.hpp"
#include "mocap/skeleton/bvh.hpp"

namespace mocap::sim {
namespace {

void to_frame(const TruthFrame& t, PoseFrame& f) {
  for (int s = 0; s < kSegmentCount; ++s) {
    const auto& q = t.q_earth_segment[s];
    const auto& j = t.q_parent_segment[s];
    f.q_earth_segment[s] = {float(q.w()), float(q.x()), float(q.y()), float(q.z())};
    f.q_parent_segment[s] = {float(j.w()), float(j.x()), float(j.y()), float(j.z())};
    const auto& p = t.p_earth_segment_m[s];
    f.p_earth_segment_m[s] = {float(p.x()), float(p.y()), float(p.z())};
  }
}

TEST(BvhMotion, WalkRoundTripsThroughABvhFile) {
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("mocap_sim_walk_" + std::to_string(getpid()) + ".bvh"))
                               .string();
  PerformerParams p;
  p.motion = "walk";
  p.loop = false;
  Performer original(p);
  {
    BvhWriter w(path, BodyModel(original.dims()), {1.0 / 60, 100.0});
    PoseFrame f;
    TruthFrame t;
    for (int k = 0; k * (1.0 / 60) <= 8.0; ++k) {
      original.truth_at(4.0 + k / 60.0, t);
      to_frame(t, f);
      w.write_frame(f);
    }
  }
  auto motion = std::shared_ptr<const Motion>(make_bvh_motion(path, 3.0, 1.0));
  std::filesystem::remove(path);
  EXPECT_NEAR(motion->duration_s(), 3.0 + 1.0 + 8.0, 1.0 / 60 + 1e-9);
  EXPECT_EQ(motion->calibration_window_s().second, 3.0);
  Performer replay(p, motion);
  TruthFrame a, b;
  double worst_deg = 0, worst_m = 0;
  for (double t = 0.5; t < 7.5; t += 0.25) {
    original.truth_at(4.0 + t, a);
    replay.truth_at(4.0 + t, b);  // lead-in 3 s + blend 1 s
    for (int s = 0; s < kSegmentCount; ++s)
      worst_deg = std::max(worst_deg,
                           a.q_earth_segment[s].angularDistance(b.q_earth_segment[s]) * 180 / M_PI);
    worst_m = std::max(worst_m, (a.p_earth_segment_m[0] - b.p_earth_segment_m[0]).norm());
  }
  EXPECT_LT(worst_deg, 1.0);
  EXPECT_LT(worst_m, 0.02);
  // The virtual sensors ride on it and the stream stays finite.
  std::vector<ImuSample> out;
  replay.step_to(6'000'000'000, out);
  ASSERT_GT(out.size(), 15u * 500);
  for (const auto& s : out)
    ASSERT_TRUE(s.acc_m_s2.allFinite() && s.gyr_rad_s.allFinite());
}

TEST(BvhMotion, MissingFileIsAnError) {
  EXPECT_THROW(make_bvh_motion("/nonexistent/walk.bvh"), std::runtime_error);
}

}  // namespace
}  // namespace mocap::sim
