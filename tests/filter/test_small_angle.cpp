// small_angle.hpp's series against libm: the filter's per-sample path takes them instead of atan2,
// asin, sincos, so they must agree with libm to a double's rounding over the range each is used on,
// and decline (fall back to libm) outside it.
#include "mocap/filter/small_angle.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace mocap {
namespace {

constexpr double kUlp = std::numeric_limits<double>::epsilon();

TEST(FilterSmallAngle, AngleGridIsLibmSinCos) {
  for (int k = -kAngleGridHalf; k <= kAngleGridHalf; ++k) {
    const double x = k / 64.0;
    const AngleGridEntry& e = kAngleGrid[k + kAngleGridHalf];
    EXPECT_NEAR(e.sin, std::sin(x), 0.5 * kUlp) << k;
    EXPECT_NEAR(e.cos, std::cos(x), 0.5 * kUlp) << k;
  }
}

TEST(FilterSmallAngle, ArctangentSeriesAreLibmsWithinTwoUlps) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 100000; ++i) {
    const double r_small = u(rng) / 16, r_quarter = u(rng) * kAtanQuarterMax;
    EXPECT_NEAR(atan_small(r_small), std::atan(r_small), 2 * kUlp * std::abs(r_small));
    EXPECT_NEAR(atan_quarter(r_quarter), std::atan(r_quarter), 2 * kUlp * std::abs(r_quarter));
  }
}

// Directions within a few degrees of the angle they are expected near are atan2 to an ulp of
// the angle; further away, off the grid or NaN, atan2_near declines and leaves the angle alone.
TEST(FilterSmallAngle, Atan2NearIsAtan2OrDeclines) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  int taken = 0;
  for (int i = 0; i < 100000; ++i) {
    const double angle = 1.55 * u(rng), n = 50 * (1.1 + u(rng));
    const double y = n * std::sin(angle), x = n * std::cos(angle);
    const double off = 0.1 * u(rng);  // the expectation's error, up to 5.7 deg
    double got = 99;
    if (atan2_near(y, x, angle + off, got)) {
      ++taken;
      EXPECT_NEAR(got, std::atan2(y, x), 2 * kUlp) << angle << " " << off;
    } else {
      EXPECT_EQ(got, 99);
      const bool off_grid = std::abs(angle + off) * 64 >= kAngleGridHalf + 0.5;
      EXPECT_TRUE(off_grid || std::abs(off) > std::atan(1.0 / 16) - 1.0 / 128 - 1e-12)
          << angle << " " << off;
    }
  }
  EXPECT_GT(taken, 50000);
  double got = 99;
  EXPECT_FALSE(atan2_near(1, 1, 2.0, got));  // anchor off the grid
  EXPECT_FALSE(atan2_near(1, 1, std::numeric_limits<double>::quiet_NaN(), got));
  EXPECT_FALSE(atan2_near(0, 0, 0.0, got));  // no direction
  EXPECT_FALSE(atan2_near(std::numeric_limits<double>::quiet_NaN(), 1, 0.0, got));
  EXPECT_EQ(got, 99);
}

}  // namespace
}  // namespace mocap
