// SpscRing: order, capacity, and a producer/consumer pair on two threads losing nothing.
#include <gtest/gtest.h>

#include <thread>

#include "mocap/core/imu_sample.hpp"
#include "mocap/core/spsc_ring.hpp"
#include "mocap/core/wakeup.hpp"

namespace mocap {

TEST(SpscRing, FifoOrderAndFullRing) {
  SpscRing<int, 4> ring;
  int out = 0;
  EXPECT_FALSE(ring.try_pop(out));
  for (int i = 0; i < 4; ++i)
    EXPECT_TRUE(ring.try_push(i));
  EXPECT_FALSE(ring.try_push(99)) << "a full ring must refuse, not overwrite";
  EXPECT_EQ(ring.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(ring.try_pop(out));
    EXPECT_EQ(out, i);
  }
  EXPECT_TRUE(ring.empty());
}

TEST(SpscRing, TwoThreadsDeliverEverySampleInOrder) {
  constexpr uint32_t kCount = 200000;
  auto ring = std::make_unique<SpscRing<ImuSample, 256>>();
  Wakeup wake;
  std::thread producer([&] {
    ImuSample s;
    for (uint32_t i = 0; i < kCount; ++i) {
      s.seq = i;
      s.gyr_rad_s.x() = i * 0.5;
      while (!ring->try_push(s))
        std::this_thread::yield();
      wake.notify();
    }
  });
  uint32_t expected = 0;
  ImuSample s;
  while (expected < kCount) {
    if (!ring->try_pop(s)) {
      wake.wait(100);
      continue;
    }
    ASSERT_EQ(s.seq, expected);
    ASSERT_EQ(s.gyr_rad_s.x(), expected * 0.5);
    ++expected;
  }
  producer.join();
  EXPECT_TRUE(ring->empty());
}

TEST(Wakeup, TimesOutWithoutNotifyAndWakesWithIt) {
  Wakeup w;
  EXPECT_FALSE(w.wait(10));
  w.notify();
  w.notify();
  EXPECT_TRUE(w.wait(0));
  EXPECT_FALSE(w.wait(0)) << "pending notifications are cleared by wait";
}

}  // namespace mocap
