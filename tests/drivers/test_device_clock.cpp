// Counter unwrapping, loss counting and the drift-tracked device-to-host clock mapping.
#include <gtest/gtest.h>

#include <random>

#include "mocap/drivers/device_clock.hpp"

using namespace mocap;

TEST(Unwrapper, Uint16CounterWrapsForward) {
  Unwrapper u(65536);
  EXPECT_EQ(u.next(65530), 65530);
  int64_t v = 0;
  for (int i = 1; i <= 10; ++i)
    v = u.next((65530 + i) % 65536);
  EXPECT_EQ(v, 65540);
  EXPECT_EQ(u.last_step(), 1);
  u.next(9);  // raw 4 -> 9: four samples skipped
  EXPECT_EQ(u.last_step(), 5);
}

TEST(Unwrapper, DayClockModulusAndBackwardStep) {
  Unwrapper u(864'000'000);
  u.next(863'999'900);
  EXPECT_EQ(u.next(100), 864'000'100);
  EXPECT_EQ(u.next(50), 864'000'050);
  EXPECT_EQ(u.last_step(), -50);
}

TEST(CounterGap, CountsDropsAndResets) {
  EXPECT_EQ(counter_gap(1, 100).dropped, 0);
  EXPECT_EQ(counter_gap(4, 100).dropped, 3);
  EXPECT_TRUE(counter_gap(0, 100).reset);
  EXPECT_TRUE(counter_gap(-3, 100).reset);
  EXPECT_TRUE(counter_gap(1000, 100).reset);
}

TEST(PeriodTracker, LearnsPeriodAndCountsSkips) {
  PeriodTracker p;
  EXPECT_EQ(p.update(10'000'000), 0);
  EXPECT_EQ(p.update(10'000'000), 0);
  EXPECT_EQ(p.period_ns(), 10'000'000);
  EXPECT_EQ(p.update(30'000'000), 2);
  EXPECT_EQ(p.update(10'100'000), 0);
}

// A device clock 200 ppm slow, read with random 0.2..3 ms latency: the mapping must recover the
// true host time of each sample far better than the latency jitter, and track the drift.
TEST(DeviceClock, TracksDriftUnderJitter) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> lat(0.2e6, 3e6);
  DeviceClock c;
  const int64_t host0 = 5'000'000'000'000;
  const double drift = 200e-6;
  double max_err_late = 0;
  bool reset = false;
  for (int i = 0; i < 20000; ++i) {  // 200 s at 100 Hz
    const int64_t t_dev = int64_t{i} * 10'000'000;
    const int64_t t_true = host0 + static_cast<int64_t>(t_dev * (1 + drift));
    const int64_t t_read = t_true + static_cast<int64_t>(lat(rng));
    const int64_t t_map = c.map(t_dev, t_read, reset);
    EXPECT_LE(t_map, t_read);
    EXPECT_FALSE(reset && i > 0);
    if (i > 2000) max_err_late = std::max(max_err_late, std::abs(double(t_map - t_true)));
  }
  EXPECT_LT(max_err_late, 0.5e6) << "mapping error should be well under the 2.8 ms jitter";
  EXPECT_NEAR(c.drift(), drift, 30e-6);
  std::printf(
      "clock: 200 ppm drift, 0.2-3 ms latency: max mapping error %.3f ms, drift est %.1f ppm\n",
      max_err_late * 1e-6, c.drift() * 1e6);
}

TEST(DeviceClock, DetectsRestart) {
  DeviceClock c;
  bool reset = false;
  c.map(0, 1'000'000'000, reset);
  EXPECT_FALSE(reset);
  c.map(10'000'000, 1'010'000'000, reset);
  EXPECT_FALSE(reset);
  c.map(0, 1'020'000'000, reset);  // device restarted
  EXPECT_TRUE(reset);
  EXPECT_EQ(c.resets(), 1u);
}
