// WitMotion: framer resync, unit conversion against the encoder's truth, configuration answers.
#include <gtest/gtest.h>

#include "collect_sink.hpp"
#include "mocap/core/units.hpp"
#include "mocap/devsim/sim_device.hpp"
#include "mocap/drivers/witmotion.hpp"

using namespace mocap;

namespace {
std::vector<uint8_t> stream(ProtocolEncoder& enc, const Motion& m, int n, int64_t period_ns) {
  std::vector<uint8_t> out;
  for (int i = 0; i < n; ++i)
    enc.encode(m.at(i * period_ns), out);
  return out;
}
}  // namespace

TEST(Witmotion, FramerChecksumAndTypes) {
  std::vector<uint8_t> b;
  witmotion::encode({witmotion::kAcc, {100, -200, 2048, 3650}}, b);
  witmotion::Framer f;
  witmotion::Packet p;
  bool got = false;
  EXPECT_EQ(f.consume(b, p, got), 11u);
  ASSERT_TRUE(got);
  EXPECT_EQ(p.d[1], -200);
  b[5] ^= 1;
  f.consume(b, p, got);
  EXPECT_FALSE(got);
  EXPECT_EQ(f.checksum_errors, 1u);
}

TEST(Witmotion, ConfiguredStreamDecodesTruth) {
  auto motion = make_motion("rotate");
  auto enc = make_encoder("witmotion", {.rate_hz = 100});
  // Configure as the driver does: unlock, enable time + quaternion too.
  DeviceSpec spec{.name = "w", .protocol = "witmotion"};
  std::vector<uint8_t> reply;
  for (auto cmd : {witmotion::command(witmotion::kRegKey, witmotion::kUnlockKey),
                   witmotion::command(witmotion::kRegRsw, 0x021F)})
    enc->handle_host_bytes(cmd, reply);
  auto bytes = stream(*enc, *motion, 300, 10'000'000);
  auto dec = make_decoder(spec);
  test::CollectSink sink;
  // Random chunking, with garbage in the middle.
  std::vector<uint8_t> garbage = {0x55, 0x51, 0x00, 0x13, 0x55, 0x55, 0xAA, 0x01};
  bytes.insert(bytes.begin() + 1500, garbage.begin(), garbage.end());
  for (std::size_t off = 0; off < bytes.size(); off += 7)
    dec->feed(std::span(bytes).subspan(off, std::min<std::size_t>(7, bytes.size() - off)), 0, sink);
  ASSERT_GE(sink.samples.size(), 298u);
  EXPECT_GE(dec->stats().resyncs, 1u);
  double max_gyr = 0, max_acc = 0, max_q = 0;
  int complete = 0;
  for (const auto& s : sink.samples) {
    // The garbage breaks one packet: that cycle's sample lacks a field, the others are whole.
    if (!(s.has(kFieldQuat) && s.has(kFieldGyr) && s.has(kFieldAcc) && s.has(kFieldMag))) continue;
    ++complete;
    const ImuSample truth = motion->at(s.t_device_ns);
    max_gyr = std::max(max_gyr, (s.gyr_rad_s - truth.gyr_rad_s).cwiseAbs().maxCoeff());
    max_acc = std::max(max_acc, (s.acc_m_s2 - truth.acc_m_s2).cwiseAbs().maxCoeff());
    max_q = std::max(max_q, s.q_device_sensor.angularDistance(truth.q_device_sensor));
  }
  EXPECT_GE(complete, 298);
  // With time packets every sample is timed by the device's clock (a reader may batch its reads).
  EXPECT_EQ(dec->stats().timed_samples, dec->stats().samples);
  EXPECT_LT(max_gyr, 2000.0 / 32768 * kRadPerDeg);  // one LSB
  EXPECT_LT(max_acc, 16 * 9.80665 / 32768);
  EXPECT_LT(max_q, 1e-3);
}

// Without the time packet (the power-on output content) samples are stamped at read: none is
// timed, so a reader never batches them (their times would bunch).
TEST(Witmotion, UntimedStreamCountsNoTimedSamples) {
  auto motion = make_motion("rotate");
  auto enc = make_encoder("witmotion", {.rate_hz = 100});
  const auto bytes = stream(*enc, *motion, 50, 10'000'000);
  auto dec = make_decoder(DeviceSpec{.name = "w", .protocol = "witmotion"});
  test::CollectSink sink;
  dec->feed(bytes, 1'000'000, sink);
  EXPECT_GE(dec->stats().samples, 48u);
  EXPECT_EQ(dec->stats().timed_samples, 0u);
}

TEST(Witmotion, WritesNeedUnlockAndRegisterReadReplies) {
  auto enc = make_encoder("witmotion", {.rate_hz = 10});
  std::vector<uint8_t> reply;
  enc->handle_host_bytes(witmotion::command(witmotion::kRegRate, witmotion::rate_code(200)), reply);
  EXPECT_DOUBLE_EQ(enc->rate_hz(), 10);  // locked: ignored
  enc->handle_host_bytes(witmotion::command(witmotion::kRegKey, witmotion::kUnlockKey), reply);
  enc->handle_host_bytes(witmotion::command(witmotion::kRegRate, witmotion::rate_code(200)), reply);
  EXPECT_DOUBLE_EQ(enc->rate_hz(), 200);
  enc->handle_host_bytes(witmotion::command(witmotion::kRegRead, witmotion::kRegRsw), reply);
  ASSERT_EQ(reply.size(), 11u);
  EXPECT_EQ(reply[1], witmotion::kRegReply);
  EXPECT_EQ(reply[2], 0x1E);                        // RSW default
  EXPECT_EQ(reply[6], witmotion::baud_code(9600));  // register 0x04 = BAUD
  enc->handle_host_bytes(witmotion::command(witmotion::kRegBaud, witmotion::baud_code(115200)),
                         reply);
  enc->handle_host_bytes(witmotion::command(witmotion::kRegRead, witmotion::kRegRsw), reply);
  ASSERT_EQ(reply.size(), 22u);
  EXPECT_EQ(reply[11 + 6], witmotion::baud_code(115200));
}

TEST(Witmotion, QuaternionOrderOption) {
  auto motion = make_motion("rotate");
  auto enc = make_encoder("witmotion",
                          {.rate_hz = 100, .options = {{"quat_order", "xyzw"}, {"rsw", "512"}}});
  std::vector<uint8_t> b;
  enc->encode(motion->at(300'000'000), b);
  DeviceSpec spec{.name = "w", .protocol = "witmotion", .options = {{"quat_order", "xyzw"}}};
  auto dec = make_decoder(spec);
  test::CollectSink sink;
  dec->feed(b, 0, sink);
  dec->feed(b, 0, sink);  // the second cycle completes the first
  ASSERT_GE(sink.samples.size(), 1u);
  EXPECT_LT(
      sink.samples[0].q_device_sensor.angularDistance(motion->at(300'000'000).q_device_sensor),
      1e-3);
}
