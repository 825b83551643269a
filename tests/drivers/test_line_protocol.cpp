// Line protocol: parsing, checksums, units, wrap-around, resync on garbage.
#include <gtest/gtest.h>

#include "collect_sink.hpp"
#include "mocap/drivers/line_protocol.hpp"

using namespace mocap;

static std::span<const uint8_t> bytes(const std::string& s) {
  return {reinterpret_cast<const uint8_t*>(s.data()), s.size()};
}

TEST(LineProtocol, DecodesWithDeclaredUnits) {
  DeviceSpec spec{.name = "t", .protocol = "line"};
  auto dec = make_decoder(spec);
  test::CollectSink sink;
  std::string in = "#units t=ms acc=mg gyr=rad/s mag=G\n";
  in += line::format_line(1000, {0, 0, 1000, 0.1, 0.2, 0.3, 0.2, 0, -0.4}, true);
  in += line::format_line(1010, {0, 0, 1000, 0.1, 0.2, 0.3, 0.2, 0, -0.4}, false);
  dec->feed(bytes(in), 42, sink);
  ASSERT_EQ(sink.samples.size(), 2u);
  const auto& s = sink.samples[1];
  EXPECT_NEAR(s.acc_m_s2.z(), 9.80665, 1e-9);
  EXPECT_NEAR(s.gyr_rad_s.y(), 0.2, 1e-12);
  EXPECT_NEAR(s.mag_uT.x(), 20.0, 1e-9);
  EXPECT_EQ(s.t_device_ns - sink.samples[0].t_device_ns, 10'000'000);
}

TEST(LineProtocol, GarbageBadChecksumAndWrap) {
  DeviceSpec spec{.name = "t", .protocol = "line"};
  auto dec = make_decoder(spec);
  test::CollectSink sink;
  std::string in;
  in += line::format_line(4294967000u, {0, 0, 1, 0, 0, 0, 0, 0, 0}, true);
  in += std::string("\x01\xff garbage 1 2 nan\n", 19);
  std::string bad = line::format_line(4294967100u, {0, 0, 1, 0, 0, 0, 0, 0, 0}, true);
  bad[3] = bad[3] == '1' ? '2' : '1';  // corrupt a digit: checksum must catch it
  in += bad;
  in += std::string(500, 'x') + "\n";  // overlong line
  in += line::format_line(4294967200u, {0, 0, 1, 0, 0, 0, 0, 0, 0}, true);
  in += line::format_line(4294967296u + 104u, {0, 0, 1, 0, 0, 0, 0, 0, 0}, true);  // wrapped
  for (char c : in)
    dec->feed(bytes(std::string(1, c)), 0, sink);  // byte by byte
  ASSERT_EQ(sink.samples.size(), 3u);
  EXPECT_EQ(dec->stats().checksum_errors, 1u);
  EXPECT_GE(dec->stats().resyncs, 2u);
  EXPECT_EQ(sink.samples[2].t_device_ns - sink.samples[1].t_device_ns, 200'000);
  EXPECT_EQ(dec->stats().dropped_samples, 0u);
}

TEST(LineProtocol, RejectsBadUnitsOption) {
  DeviceSpec spec{.name = "t", .protocol = "line", .options = {{"units", "acc=furlongs"}}};
  EXPECT_THROW(make_decoder(spec), std::invalid_argument);
}
