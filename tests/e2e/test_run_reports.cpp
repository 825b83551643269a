// `mocap replay` and `mocap export` report on the same stream in the same form (issue 22 item
// 12): one JSON line on stdout with the same leading keys, warnings on stderr; a replay without
// any calibration warns, a calibrated one does not.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "../common/run_program.hpp"
#include "mocap/session/session_reader.hpp"
#include "mocap/session/session_writer.hpp"

namespace fs = std::filesystem;
using mocap::test::Result;
using mocap::test::run;

namespace {

const std::string kBin = std::string(MOCAP_BINARY_DIR) + "/bin/";

/// The one JSON line a command printed on stdout (fails the test if it is not exactly that).
nlohmann::ordered_json summary_of(const Result& r) {
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
  auto j = nlohmann::ordered_json::parse(r.out, nullptr, false);
  EXPECT_TRUE(j.is_object()) << r.out;
  return j;
}

/// A copy of `from` (header, samples) with the poses of its replay appended: a session as
/// mocapd records it, for `mocap export`.
void write_session_with_poses(const std::string& from, const std::string& to) {
  mocap::SessionReader r;
  std::string err;
  ASSERT_TRUE(r.open(from, &err)) << err;
  std::vector<mocap::ImuSample> samples;
  mocap::SessionReader::Block b;
  while (r.next(b))
    if (b.type == mocap::session::BlockType::sample) samples.push_back(b.sample);
  ASSERT_FALSE(samples.empty());
  const std::string csv = to + ".poses.csv";
  const Result rep = run({kBin + "mocap", "replay", from, "--csv", csv, "--quiet"});
  ASSERT_EQ(rep.code, 0) << rep.err;
  auto w = mocap::SessionWriter::create(to, r.header(), {}, &err);
  ASSERT_TRUE(w) << err;
  for (const auto& s : samples)
    ASSERT_TRUE(w->append_sample(s));
  // Poses from the replay's CSV (t,segment,w,x,y,z,px,py,pz; one row per segment).
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  mocap::PoseFrame f;
  mocap::reset_pose(f);
  int seg = 0;
  uint64_t n = 0;
  while (std::getline(in, line)) {
    double v[8];
    char name[32];
    if (std::sscanf(line.c_str(), "%lf,%31[^,],%lf,%lf,%lf,%lf,%lf,%lf,%lf", &v[0], name, &v[1],
                    &v[2], &v[3], &v[4], &v[5], &v[6], &v[7]) != 9)
      continue;
    f.q_earth_segment[seg] = {static_cast<float>(v[1]), static_cast<float>(v[2]),
                              static_cast<float>(v[3]), static_cast<float>(v[4])};
    f.p_earth_segment_m[seg] = {static_cast<float>(v[5]), static_cast<float>(v[6]),
                                static_cast<float>(v[7])};
    f.segment_flags[seg] = mocap::kSegTracked;
    if (++seg == mocap::kSegmentCount) {
      f.frame = n++;
      // The replay's CSV times count from the first sample.
      f.t_ns = samples.front().t_host_ns + static_cast<int64_t>(std::llround(v[0] * 1e9));
      ASSERT_TRUE(w->append_pose(f));
      seg = 0;
    }
  }
  ASSERT_TRUE(w->close());
}

std::vector<std::string> keys_of(const nlohmann::ordered_json& j, size_t n) {
  std::vector<std::string> k;
  for (auto it = j.begin(); it != j.end() && k.size() < n; ++it)
    k.push_back(it.key());
  return k;
}

}  // namespace

// Outside the anonymous namespace: gtest derives each test from it.
class RunReports : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("mocap-reports-" + std::to_string(getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const char* name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

TEST_F(RunReports, ReplayAndExportPrintTheSameSummary) {
  const std::string session = std::string(MOCAP_SOURCE_DIR) + "/tests/data/demo_direct_50hz.mcap";
  const Result rep = run({kBin + "mocap", "replay", session, "--csv", path("r.csv"), "--quiet"});
  ASSERT_EQ(rep.code, 0) << rep.err;
  // The golden session holds samples only: export the poses its replay would have recorded.
  const std::string with_poses = path("p.mocapses");
  write_session_with_poses(session, with_poses);
  const Result exp = run({kBin + "mocap", "export", with_poses, "--csv", path("e.csv")});
  ASSERT_EQ(exp.code, 0) << exp.err;
  const auto r = summary_of(rep), e = summary_of(exp);
  const std::vector<std::string> common = {"command", "input", "outputs", "frames", "duration_s"};
  EXPECT_EQ(keys_of(r, 5), common);
  EXPECT_EQ(keys_of(e, 5), common);
  EXPECT_EQ(r["command"], "replay");
  EXPECT_EQ(e["command"], "export");
  EXPECT_EQ(r["input"], session);
  EXPECT_EQ(e["input"], with_poses);
  EXPECT_EQ(r["outputs"], nlohmann::ordered_json::array({path("r.csv")}));
  EXPECT_EQ(e["outputs"], nlohmann::ordered_json::array({path("e.csv")}));
  EXPECT_GT(r["frames"].get<long>(), 10);
  EXPECT_GT(e["frames"].get<long>(), 10);
  // The same recording: the poses span the samples' time, within a frame or two.
  EXPECT_EQ(r["frames"], e["frames"]);
  EXPECT_NEAR(r["duration_s"].get<double>(), e["duration_s"].get<double>(), 0.1);
  // Diagnostics on stderr, never in the summary stream (this session is uncalibrated: warned).
  EXPECT_NE(rep.err.find("warning"), std::string::npos) << rep.err;
  EXPECT_EQ(rep.out.find("warning"), std::string::npos) << rep.out;
}

TEST_F(RunReports, UncalibratedReplayWarns) {
  const Result perf = run({kBin + "mocap", "perform", "--motion", "npose", "--duration", "3",
                           "--samples", path("s.csv")});
  ASSERT_EQ(perf.code, 0) << perf.err;
  const Result plain = run({kBin + "mocap", "replay", path("s.csv"), "--quiet"});
  ASSERT_EQ(plain.code, 0) << plain.err;
  EXPECT_NE(plain.err.find("warning"), std::string::npos) << plain.err;
  EXPECT_NE(plain.err.find("no calibration"), std::string::npos) << plain.err;
  EXPECT_FALSE(summary_of(plain)["calibrated"].get<bool>());
  const Result cal =
      run({kBin + "mocap", "replay", path("s.csv"), "--calibrate", "npose@1.0", "--quiet"});
  ASSERT_EQ(cal.code, 0) << cal.err;
  EXPECT_EQ(cal.err.find("no calibration"), std::string::npos) << cal.err;
  EXPECT_TRUE(summary_of(cal)["calibrated"].get<bool>());
}
