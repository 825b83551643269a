// `mocap bench latency [--protocol slimevr]|capacity|replay|record` in tiny configurations: they
// run, exit 0 and print one JSON object whose counts are consistent. No timing is asserted (shared
// machines).
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include <nlohmann/json.hpp>

namespace {

nlohmann::json run_bench(const std::string& args) {
  const std::string cmd = std::string(MOCAP_BINARY_DIR) + "/bin/mocap bench " + args;
  FILE* p = ::popen(cmd.c_str(), "r");
  EXPECT_NE(p, nullptr);
  std::string out;
  char buf[4096];
  while (size_t n = std::fread(buf, 1, sizeof buf, p))
    out.append(buf, n);
  EXPECT_EQ(::pclose(p), 0) << cmd << "\n" << out;
  return nlohmann::json::parse(out);  // throws (test fails) unless exactly one JSON value
}

TEST(BenchDaemon, LatencyMatchesEveryWrite) {
  const auto j = run_bench("latency --sensors 3 --rate 50 --duration 1");
  EXPECT_EQ(j.at("benchmark"), "latency");
  EXPECT_EQ(j.at("written").get<int>(), 150);
  EXPECT_EQ(j.at("matched").get<int>() + j.at("unmatched").get<int>(), 150);
  EXPECT_GT(j.at("matched").get<int>(), 0);
  const auto& l = j.at("latency_ms");
  EXPECT_GE(l.at("p50").get<double>(), 0.0);
  EXPECT_LE(l.at("p50").get<double>(), l.at("p99").get<double>());
  EXPECT_LE(l.at("p99").get<double>(), l.at("max").get<double>());
  EXPECT_TRUE(j.at("pass").is_boolean());
}

TEST(BenchDaemon, LatencySlimeVrRunsBothPaths) {
  const auto j = run_bench("latency --protocol slimevr --sensors 3 --rate 50 --duration 1");
  EXPECT_EQ(j.at("protocol"), "slimevr");
  for (const char* path : {"slimevr", "witmotion"}) {
    const auto& p = j.at(path);
    EXPECT_EQ(p.at("written").get<int>(), 150) << path;
    EXPECT_EQ(p.at("matched").get<int>() + p.at("unmatched").get<int>(), 150) << path;
    EXPECT_GT(p.at("matched").get<int>(), 0) << path;
  }
  EXPECT_GT(j.at("p99_ratio_slimevr_to_witmotion").get<double>(), 0.0);
  EXPECT_TRUE(j.at("pass").is_boolean());
}

TEST(BenchDaemon, CapacityCountsSamples) {
  const auto j = run_bench("capacity --sensors 3 --rate 100 --duration 1");
  EXPECT_EQ(j.at("benchmark"), "capacity");
  for (const char* run : {"run", "baseline"}) {  // the baseline: the same load, read unbatched
    const auto& r = j.at(run);
    const auto& s = r.at("samples");
    EXPECT_EQ(s.at("written").get<int>(), 300) << run;
    EXPECT_GE(s.at("received").get<int>() + s.at("lost").get<int>(), 300) << run;
    EXPECT_GT(s.at("received").get<int>(), 0) << run;
    EXPECT_GT(r.at("daemon_rss_mb").at("max").get<double>(), 0.0) << run;
    EXPECT_GE(r.at("daemon_cpu_pct_of_one_core").get<double>(), 0.0) << run;
  }
  EXPECT_EQ(j.at("baseline").at("read_batch_ms").get<double>(), 0.0);
  EXPECT_TRUE(j.at("pass").is_boolean());
}

// Several performers (one mocapd each) over UDP with the line protocol: every sample counted.
TEST(BenchDaemon, CapacityOfPerformersOverUdp) {
  const auto j = run_bench(
      "capacity --protocol line-udp --performers 2 --sensors 2 --rate 100 --duration 1 "
      "--no-baseline");
  EXPECT_EQ(j.at("params").at("sensors").get<int>(), 4);
  EXPECT_TRUE(j.at("baseline").is_null());
  const auto& s = j.at("run").at("samples");
  EXPECT_EQ(s.at("written").get<int>(), 400);
  EXPECT_GE(s.at("received").get<int>() + s.at("lost").get<int>(), 400);
  EXPECT_GT(s.at("received").get<int>(), 0);
  EXPECT_GE(j.at("run").at("daemon_cpu_us_per_sample").get<double>(), 0.0);
}

TEST(BenchDaemon, ReplayReplaysEverySample) {
  const auto j = run_bench("replay --minutes 0.1");
  EXPECT_EQ(j.at("benchmark"), "replay");
  const auto& s = j.at("samples");
  EXPECT_NEAR(s.at("generated").get<int>(), 17 * 600, 17 * 2);
  EXPECT_EQ(s.at("baseline_read").get<int>(), s.at("generated").get<int>());
  EXPECT_EQ(s.at("replayed").get<int>(), s.at("generated").get<int>());
  EXPECT_GT(j.at("frames").get<int>(), 0);
  EXPECT_GT(j.at("bvh_mb").get<double>(), 0.0);
  EXPECT_GT(j.at("ratio_to_baseline").get<double>(), 0.0);
}

TEST(BenchDaemon, RecordCompressesEverySettingWithoutDrops) {
  const auto j = run_bench("record --duration 3 --repeat 1");
  EXPECT_EQ(j.at("benchmark"), "record");
  EXPECT_GT(j.at("input").at("poses").get<int>(), 0);
  EXPECT_GT(j.at("input").at("raw").get<int>(), 0);
  const auto& s = j.at("settings");
  ASSERT_EQ(s.size(), 4u);
  EXPECT_EQ(s[0].at("compression"), "none");
  EXPECT_DOUBLE_EQ(s[0].at("size_ratio").get<double>(), 1.0);
  for (const auto& r : s) {
    EXPECT_EQ(r.at("dropped").get<int>(), 0) << r;
    EXPECT_GT(r.at("file_mb").get<double>(), 0.0) << r;
  }
  for (std::size_t i = 1; i < s.size(); ++i)  // zstd always packs a recording
    EXPECT_GT(s[i].at("size_ratio").get<double>(), 1.2) << s[i];
}

}  // namespace
