// Readings a sensor cannot make, behind valid checksums: beyond 1.1 x full scale the field is
// dropped and the sample flagged kFlagImplausible; at >= 0.99 x full scale (clipped or pegged)
// the sample is flagged kFlagSaturated; both are counted in the decoder's stats.
#include <gtest/gtest.h>

#include <cmath>

#include "collect_sink.hpp"
#include "mocap/drivers/line_protocol.hpp"
#include "mocap/drivers/witmotion.hpp"

using namespace mocap;

namespace {
std::span<const uint8_t> as_bytes(const std::string& s) {
  return {reinterpret_cast<const uint8_t*>(s.data()), s.size()};
}
std::string sample_line(uint64_t t_us, double acc_z_g, double gyr_x_dps) {
  return line::format_line(t_us, {0, 0, acc_z_g, gyr_x_dps, 0, 0, 20, 0, -40}, true);
}
}  // namespace

TEST(Plausibility, LineSensorGlitchesAreDroppedFlaggedAndCounted) {
  auto dec = make_decoder({.name = "l", .protocol = "line"});  // default range 2000 dps, 16 g
  test::CollectSink sink;
  std::string in;
  in += sample_line(0, 1, 0);
  in +=
      sample_line(10'000, 1, 5000);  // 5000 deg/s at rest: beyond any reading of a 2000 deg/s gyro
  in += sample_line(20'000, 40, 0);  // 40 g then rest
  in += sample_line(30'000, 1, 1995);  // pegged at full scale: kept, flagged saturated
  in += sample_line(40'000, 1, 0.5);
  in += sample_line(50'000, 15.9, 0);  // acc at full scale: saturated, but no rotation lost
  dec->feed(as_bytes(in), 0, sink);
  ASSERT_EQ(sink.samples.size(), 6u);
  const auto& s = sink.samples;
  EXPECT_EQ(s[0].flags & (kFlagImplausible | kFlagSaturated), 0);
  EXPECT_TRUE(s[1].flags & kFlagImplausible);
  EXPECT_FALSE(s[1].has(kFieldGyr));
  EXPECT_TRUE(s[1].has(kFieldAcc));
  EXPECT_TRUE(s[2].flags & kFlagImplausible);
  EXPECT_FALSE(s[2].has(kFieldAcc));
  EXPECT_TRUE(s[2].has(kFieldGyr));
  EXPECT_TRUE(s[3].flags & kFlagSaturated);
  EXPECT_FALSE(s[3].flags & kFlagImplausible);
  EXPECT_TRUE(s[3].has(kFieldGyr));
  EXPECT_TRUE(s[3].flags & kFlagGyrClipped);  // the filter's cue for upset recovery
  EXPECT_EQ(s[4].flags & (kFlagImplausible | kFlagSaturated), 0);
  EXPECT_TRUE(s[5].flags & kFlagSaturated);
  EXPECT_FALSE(s[5].flags & kFlagGyrClipped);
  EXPECT_EQ(dec->stats().implausible, 2u);
  EXPECT_EQ(dec->stats().saturated, 2u);
  EXPECT_EQ(dec->stats().checksum_errors, 0u);
}

TEST(Plausibility, RangeOptionsWidenTheLimits) {
  auto dec = make_decoder({.name = "l",
                           .protocol = "line",
                           .options = {{"gyr_range_dps", "4000"}, {"acc_range_g", "64"}}});
  test::CollectSink sink;
  dec->feed(as_bytes(sample_line(0, 40, 3000)), 0, sink);
  ASSERT_EQ(sink.samples.size(), 1u);
  EXPECT_TRUE(sink.samples[0].has(kFieldGyr) && sink.samples[0].has(kFieldAcc));
  EXPECT_EQ(dec->stats().implausible + dec->stats().saturated, 0u);
  EXPECT_THROW(make_decoder({.name = "l", .protocol = "line", .options = {{"acc_range_g", "0"}}}),
               std::invalid_argument);
}

TEST(Plausibility, WitmotionPeggedGyroIsFlaggedSaturated) {
  // A 0x52 packet with x at the int16 limit: 2000 deg/s (the wire's full scale).
  auto dec = make_decoder({.name = "w", .protocol = "witmotion"});
  test::CollectSink sink;
  std::vector<uint8_t> b;
  witmotion::encode({witmotion::kAcc, {0, 0, 2048, 0}}, b);
  witmotion::encode({witmotion::kGyr, {32767, 3, -2, 0}}, b);
  witmotion::encode({witmotion::kAcc, {0, 0, 2048, 0}}, b);  // next cycle: ends the sample
  witmotion::encode({witmotion::kGyr, {1, 3, -2, 0}}, b);
  witmotion::encode({witmotion::kAcc, {0, 0, 2048, 0}}, b);
  dec->feed(b, 0, sink);
  ASSERT_GE(sink.samples.size(), 2u);
  EXPECT_TRUE(sink.samples[0].flags & kFlagSaturated);
  EXPECT_TRUE(sink.samples[0].has(kFieldGyr));
  EXPECT_FALSE(sink.samples[1].flags & kFlagSaturated);
  EXPECT_EQ(dec->stats().saturated, 1u);
}
