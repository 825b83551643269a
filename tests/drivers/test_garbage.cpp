// Every decoder on random bytes (as from a wrong baud rate or line noise): never crashes, emits
// only finite values, counts resyncs; and recovers valid frames that follow the garbage.
#include <gtest/gtest.h>

#include <random>

#include "collect_sink.hpp"
#include "mocap/devsim/sim_device.hpp"

using namespace mocap;

TEST(Garbage, RandomBytesThenValidStream) {
  for (const char* proto : {"line", "witmotion", "xbus"}) {
    std::mt19937 rng(99);
    std::vector<uint8_t> noise(64 * 1024);
    for (auto& b : noise)
      b = static_cast<uint8_t>(rng());
    auto dec = make_decoder({.name = "g", .protocol = proto});
    test::CollectSink sink;
    for (std::size_t off = 0; off < noise.size(); off += 61)
      dec->feed(std::span(noise).subspan(off, std::min<std::size_t>(61, noise.size() - off)), 0,
                sink);
    const std::size_t from_noise = sink.samples.size();
    for (const auto& s : sink.samples) {
      EXPECT_TRUE(s.gyr_rad_s.allFinite() && s.acc_m_s2.allFinite() && s.mag_uT.allFinite())
          << proto;
    }
    // Resyncs count garbage runs (pure noise may be one long run); nothing plausible came out.
    EXPECT_GE(dec->stats().resyncs, 1u) << proto;
    EXPECT_LT(from_noise, 5u) << proto;
    // Then the real device: every sample of a valid stream decodes.
    auto enc = make_encoder(proto, {.rate_hz = 100});
    auto motion = make_motion("rotate");
    std::vector<uint8_t> good;
    for (int i = 0; i < 50; ++i)
      enc->encode(motion->at(int64_t{i} * 10'000'000), good);
    dec->feed(good, 0, sink);
    EXPECT_GE(sink.samples.size() - from_noise, 48u) << proto;  // WitMotion emits a cycle late
    std::printf("%s: 64 KiB of noise -> %zu spurious samples, %llu resyncs, %llu checksum errors\n",
                proto, from_noise, (unsigned long long)dec->stats().resyncs,
                (unsigned long long)dec->stats().checksum_errors);
  }
}
