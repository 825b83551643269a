// Line protocol: parsing, checksums, units, wrap-around, resync on garbage.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <string>
#include <vector>

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

// Fractional time values keep their fraction in every unit (issue 22 item 1): the whole part is
// the counter that wraps, the fraction is added after the unit applies.
TEST(LineProtocol, FractionalTimeInEveryUnit) {
  struct Case {
    const char* unit;
    std::vector<std::string> times;
    std::vector<int64_t> expect_ns;
  };
  const std::vector<Case> cases = {
      {"s", {"12.5", "12.51", "12.52"}, {12'500'000'000, 12'510'000'000, 12'520'000'000}},
      {"ms", {"1002.5", "1003", "1012.25"}, {1'002'500'000, 1'003'000'000, 1'012'250'000}},
      {"us", {"100.5", "200.25"}, {100'500, 200'250}},
      {"ns", {"7.4", "9"}, {7, 9}},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.unit);
    DeviceSpec spec{.name = "t", .protocol = "line"};
    auto dec = make_decoder(spec);
    test::CollectSink sink;
    std::string in = std::string("#units t=") + c.unit + "\n";
    for (const auto& t : c.times)
      in += t + " 0 0 1 0 0 0 0 0 0\n";
    dec->feed(bytes(in), 0, sink);
    ASSERT_EQ(sink.samples.size(), c.times.size());
    for (std::size_t i = 0; i < c.times.size(); ++i)
      EXPECT_EQ(sink.samples[i].t_device_ns - sink.samples[0].t_device_ns,
                c.expect_ns[i] - c.expect_ns[0])
          << c.times[i];
    EXPECT_EQ(sink.samples[0].t_device_ns, c.expect_ns[0]);
  }
}

// An integer counter still wraps (micros() at 2^32) when a fractional value is in between.
TEST(LineProtocol, FractionalTimeAcrossTheWrap) {
  DeviceSpec spec{.name = "t", .protocol = "line"};
  auto dec = make_decoder(spec);
  test::CollectSink sink;
  const std::string in =
      "4294967000.5 0 0 1 0 0 0 0 0 0\n"
      "4294967200 0 0 1 0 0 0 0 0 0\n"
      "104.5 0 0 1 0 0 0 0 0 0\n";
  dec->feed(bytes(in), 0, sink);
  ASSERT_EQ(sink.samples.size(), 3u);
  EXPECT_EQ(sink.samples[1].t_device_ns - sink.samples[0].t_device_ns, 199'500);
  EXPECT_EQ(sink.samples[2].t_device_ns - sink.samples[1].t_device_ns, 200'500);
}

// Every line-protocol example in docs/devices.md (a fenced block holding a "#units" line) is fed
// to the real decoder: each sample line must decode, with its checksum (issue 22 item 2).
TEST(LineProtocol, DocsExamplesDecode) {
  std::ifstream f(std::string(MOCAP_SOURCE_DIR) + "/docs/devices.md");
  ASSERT_TRUE(f) << "docs/devices.md not found";
  std::vector<std::vector<std::string>> blocks;
  std::vector<std::string> cur;
  bool in_block = false;
  for (std::string l; std::getline(f, l);) {
    if (l.rfind("```", 0) == 0) {
      if (in_block) blocks.push_back(cur);
      cur.clear();
      in_block = !in_block;
      continue;
    }
    if (in_block) cur.push_back(l);
  }
  int examples = 0, sample_lines = 0, checksummed = 0;
  for (const auto& b : blocks) {
    const bool is_line_example = std::any_of(
        b.begin(), b.end(), [](const std::string& l) { return l.rfind("#units", 0) == 0; });
    if (!is_line_example) continue;
    ++examples;
    DeviceSpec spec{.name = "docs", .protocol = "line"};
    auto dec = make_decoder(spec);
    test::CollectSink sink;
    std::size_t expect = 0;
    for (const auto& l : b) {
      SCOPED_TRACE(l);
      if (l.empty() || l[0] == '#') {
        dec->feed(bytes(l + "\n"), 0, sink);
        continue;
      }
      ++expect;
      if (l.find('*') != std::string::npos) ++checksummed;
      const auto before = dec->stats();
      dec->feed(bytes(l + "\n"), 0, sink);
      EXPECT_EQ(dec->stats().checksum_errors, before.checksum_errors) << "bad checksum";
      EXPECT_EQ(dec->stats().resyncs, before.resyncs) << "malformed line";
      EXPECT_EQ(sink.samples.size(), expect) << "line not decoded";
    }
    sample_lines += static_cast<int>(expect);
  }
  EXPECT_GE(examples, 1) << "no line-protocol example found in docs/devices.md";
  EXPECT_GE(sample_lines, 2);
  EXPECT_GE(checksummed, 1);
}
