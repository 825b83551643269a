// Performer: sensor id mapping, deterministic streams, time order, drops flagged, jitter bounded,
// no allocation per sample after warm-up.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "mocap/sim/performer.hpp"

// Counts heap allocations in this test program (test-only instrumentation).
static std::atomic<long> g_allocations{0};
void* operator new(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}

namespace mocap::sim {
namespace {

TEST(Performer, FifteenSensorsNamedAfterSegmentsNoNeck) {
  for (int id = 0; id < Performer::kSensorCount; ++id) {
    EXPECT_NE(Performer::sensor_segment(id), Segment::neck);
    EXPECT_EQ(Performer::sensor_of(Performer::sensor_segment(id)), id);
    EXPECT_EQ(Performer::sensor_name(id), name(Performer::sensor_segment(id)));
  }
  EXPECT_EQ(Performer::sensor_of(Segment::neck), -1);
  EXPECT_EQ(Performer::sensor_segment(14), Segment::foot_r);
}

TEST(Performer, DeterministicPerSeedAndDifferentAcrossSeeds) {
  PerformerParams p;
  p.motion = "walk";
  std::vector<ImuSample> a, b, c;
  Performer pa(p), pb(p);
  p.seed = 2;
  Performer pc(p);
  pa.step_to(4'000'000'000, a);
  pb.step_to(4'000'000'000, b);
  pc.step_to(4'000'000'000, c);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].t_host_ns, b[i].t_host_ns);
    ASSERT_EQ(a[i].gyr_rad_s, b[i].gyr_rad_s);
    ASSERT_EQ(a[i].mag_uT, b[i].mag_uT);
  }
  ASSERT_FALSE(c.empty());
  EXPECT_NE(a[20].gyr_rad_s, c[20].gyr_rad_s);
}

TEST(Performer, StreamIsTimeOrderedWithBoundedJitterAndFlaggedDrops) {
  PerformerParams p;
  p.motion = "sequence";
  p.sensor.drop_probability = 0.02;
  p.t0_ns = 1'000'000'000'000;
  Performer perf(p);
  std::vector<ImuSample> out;
  out.reserve(4096);
  int64_t t_prev = 0;
  std::array<int64_t, Performer::kSensorCount> last_seq;
  last_seq.fill(-1);
  int gaps = 0, samples = 0;
  int64_t t_last = 0;
  for (int64_t t = p.t0_ns; t <= p.t0_ns + 10'000'000'000; t += 16'666'667) {
    out.clear();
    t_last = t;
    perf.step_to(t, out);
    for (const ImuSample& s : out) {
      ASSERT_LE(s.t_host_ns, t);
      ASSERT_GE(s.t_host_ns, t_prev);
      t_prev = s.t_host_ns;
      ASSERT_LT(s.sensor_id, Performer::kSensorCount);
      const int64_t nominal = p.t0_ns + static_cast<int64_t>(s.seq) * 10'000'000;
      ASSERT_LE(std::llabs(s.t_host_ns - nominal), 4'000'000);  // jitter clamped to 40%
      const bool gap = s.seq != last_seq[s.sensor_id] + 1;
      EXPECT_EQ(gap, (s.flags & kFlagGapBefore) != 0) << "seq " << s.seq;
      gaps += gap;
      last_seq[s.sensor_id] = s.seq;
      ASSERT_TRUE(s.gyr_rad_s.allFinite() && s.acc_m_s2.allFinite() && s.mag_uT.allFinite());
      ++samples;
    }
  }
  // 10 s, 15 sensors at 100 Hz, 2% lost.
  EXPECT_NEAR(samples, 15 * 1001 * 0.98, 60);
  EXPECT_GT(gaps, 10);
  EXPECT_NEAR(perf.truth().t_s, (t_last - p.t0_ns) * 1e-9, 1e-9);
}

TEST(Performer, NoAllocationPerSampleAfterWarmUp) {
  PerformerParams p;
  Performer perf(p);
  std::vector<ImuSample> out;
  out.reserve(1024);
  perf.step_to(100'000'000, out);  // warm-up
  const long before = g_allocations.load();
  size_t total = 0;
  for (int64_t t = 100'000'000; t < 3'000'000'000; t += 10'000'000) {
    out.clear();
    perf.step_to(t, out);
    total += out.size();
  }
  EXPECT_GT(total, 4000u);
  EXPECT_EQ(g_allocations.load() - before, 0);
}

TEST(Performer, RejectsBadParametersByName) {
  PerformerParams p;
  p.rate_hz = 0;
  try {
    Performer perf(p);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("rate_hz"), std::string::npos);
  }
  p.rate_hz = 100;
  p.motion = "cartwheel";
  EXPECT_THROW(Performer{p}, std::invalid_argument);
}

}  // namespace
}  // namespace mocap::sim
