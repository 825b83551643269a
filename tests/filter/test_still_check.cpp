// The still-moment check (eval/still_check.hpp, `mocap stills`): moments found where the
// sensor is still, scored against the accelerometer; a filter left tilted by the motion before
// a moment scores that tilt, a right one about nothing.
#include <gtest/gtest.h>

#include "mocap/eval/still_check.hpp"
#include "synth.hpp"

namespace mocap {
namespace {

using test::kDeg;

/// 4 s still, a 90 deg turn about x in 2 s, 3 s still, a 1.5 s fast swing and back, 3 s still.
test::SynthConfig turns() {
  test::SynthConfig c;
  c.duration_s = 13.5;
  c.gyr_noise = 0.001;
  c.acc_noise = 0.01;
  c.gyr_true = [](double t) -> Eigen::Vector3d {
    if (t >= 4 && t < 6) return Eigen::Vector3d(45 * kDeg, 0, 0);
    if (t >= 9 && t < 9.75) return Eigen::Vector3d(0, 400 * kDeg, 0);
    if (t >= 9.75 && t < 10.5) return Eigen::Vector3d(0, -400 * kDeg, 0);
    return Eigen::Vector3d::Zero();
  };
  return c;
}

TEST(StillCheck, FindsTheMomentsAndScoresTheFilter) {
  const test::SynthStream s = test::make_stream(turns());
  StillCheckOptions o;
  double g = 0;
  const auto m = find_still_moments(s.samples, o, g);
  ASSERT_EQ(m.size(), 3u);
  EXPECT_NEAR(m[0].t_begin_s, 0, 0.02);
  EXPECT_NEAR(m[1].t_begin_s, 6, 0.05);
  EXPECT_NEAR(m[2].t_begin_s, 10.5, 0.05);
  EXPECT_NEAR(g, 9.81, 0.01);
  const SensorStills r = check_stills(s.samples, FilterParams{}, o);
  ASSERT_EQ(r.moments.size(), 2u);  // the start is where the filter settles: not scored
  EXPECT_EQ(r.stands, 2);
  EXPECT_LT(r.stand_rms_deg, 0.3);
}

TEST(StillCheck, ATiltLeftByTheMotionIsScored) {
  // The gyro reads 5 % high during the first turn: the filter is left 4.5 deg off at the
  // second moment's onset (its inclination follows acc over seconds, not at once).
  test::SynthConfig c = turns();
  test::SynthStream s = test::make_stream(c);
  for (auto& x : s.samples) {
    const double t = x.t_host_ns * 1e-9;
    if (t > 4 && t <= 6) x.gyr_rad_s *= 1.05;
  }
  FilterParams p;
  p.gyr_gain.sigma_init = 0;
  const SensorStills r = check_stills(s.samples, p, StillCheckOptions{});
  ASSERT_EQ(r.moments.size(), 2u);
  EXPECT_GT(r.moments[0].err_deg, 3.0);
  EXPECT_LT(r.moments[0].err_deg, 5.0);
  EXPECT_NEAR(r.max_t_s, 6, 0.05);
}

}  // namespace
}  // namespace mocap
