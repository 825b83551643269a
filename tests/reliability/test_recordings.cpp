// Recording never destroys data (issue 20, item 1), against the real mocapd and mocapctl:
// an existing take is never truncated (an error naming it, mocapctl exits non-zero), names
// cannot leave recording.directory (`..`, absolute paths outside it, symlinked files and
// directories), `record start` without a name picks a fresh take name, `record stop` reports
// what was recorded, and recording.auto_start after a kill -9 keeps the crashed take.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <thread>

#include "harness.hpp"
#include "mocap/session/session_reader.hpp"

using namespace mocap;
using namespace mocap::reliability;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {

/// Runs mocapctl with `args` (words); returns its exit code and stderr+stdout in `out`.
int mocapctl(const std::string& socket, const std::string& args, std::string& out) {
  std::vector<std::string> argv{"--socket", socket};
  std::istringstream words(args);
  for (std::string w; words >> w;)
    argv.push_back(w);
  const Result r = run_bin("mocapctl", argv);
  out = r.err + r.out;
  return r.code;
}

uint64_t poses_in(const std::string& path) {
  SessionReader r;
  std::string err;
  if (!r.open(path, &err)) return 0;
  SessionReader::Block b;
  uint64_t n = 0;
  while (r.next(b))
    n += b.type == session::BlockType::pose;
  return n;
}

}  // namespace

TEST(Recordings, AnExistingTakeIsNeverOverwrittenAndMocapctlSaysWhy) {
  TwoSensorDaemon setup("over");
  auto& [dir, rig, port, d] = setup;
  ASSERT_TRUE(setup.ready_and_streaming()) << d.log_text();
  std::string out;
  ASSERT_EQ(mocapctl(d.socket(), "record start take1.mocapses", out), 0) << out;
  std::this_thread::sleep_for(400ms);
  ASSERT_EQ(mocapctl(d.socket(), "record stop", out), 0) << out;
  EXPECT_NE(out.find("frames"), std::string::npos) << out;
  const std::string before = slurp_file(dir.file("take1.mocapses"));
  ASSERT_GT(before.size(), 1000u);
  // Again with the same name: refused, named, mocapctl exits non-zero, the take is untouched.
  EXPECT_NE(mocapctl(d.socket(), "record start take1.mocapses", out), 0) << out;
  EXPECT_NE(out.find("take1.mocapses"), std::string::npos) << out;
  EXPECT_NE(out.find("already exists"), std::string::npos) << out;
  EXPECT_TRUE(d.status().value("recording", "x").empty());
  std::this_thread::sleep_for(200ms);
  EXPECT_EQ(slurp_file(dir.file("take1.mocapses")), before);
  EXPECT_EQ(d.quit(), 0) << d.log_text();
}

TEST(Recordings, NamesCannotLeaveTheRecordingDirectory) {
  TempDir dir, outside;
  TwoSensorRig rig(dir);
  const std::string rec = dir.file("rec");
  ASSERT_EQ(::mkdir(rec.c_str(), 0755), 0);
  ASSERT_EQ(::mkdir((rec + "/sub").c_str(), 0755), 0);
  const std::string victim = outside.file("victim.txt");
  { std::ofstream(victim) << "precious\n"; }
  // A symlinked file and a symlinked directory inside the recording directory.
  ASSERT_EQ(::symlink(victim.c_str(), (rec + "/link.mocapses").c_str()), 0);
  ASSERT_EQ(::symlink(outside.path().c_str(), (rec + "/linkdir").c_str()), 0);
  std::string cfg = base_config(dir, free_tcp_port()) + rig.sensors_toml();
  cfg.replace(cfg.find("directory = \"" + dir.path() + "\""),
              std::string("directory = \"" + dir.path() + "\"").size(),
              "directory = \"" + rec + "\"");
  Daemon d(dir, "escape", cfg);
  ASSERT_TRUE(d.wait_ready(15s)) << d.log_text();
  struct Case {
    std::string name, expect;
  };
  const std::vector<Case> cases{
      {"../x.mocapses", ".."},
      {"sub/../../x.mocapses", ".."},
      {outside.file("abs.mocapses"), "outside recording.directory"},
      {"/etc/passwd", "outside recording.directory"},
      {"link.mocapses", "link.mocapses"},
      {"linkdir/x.mocapses", "linkdir"},
  };
  for (const auto& c : cases) {
    const auto reply = d.call("record start " + c.name);
    EXPECT_FALSE(reply.value("ok", true)) << c.name << ": " << reply.dump();
    EXPECT_NE(reply.value("error", "").find(c.expect), std::string::npos)
        << c.name << ": " << reply.dump();
    EXPECT_TRUE(d.status().value("recording", "x").empty()) << c.name;
  }
  EXPECT_EQ(slurp_file(victim), "precious\n");
  EXPECT_FALSE(fs::exists(dir.file("x.mocapses")));
  EXPECT_FALSE(fs::exists(outside.file("x.mocapses")));
  EXPECT_FALSE(fs::exists(outside.file("abs.mocapses")));
  // Inside the directory: relative with a subdirectory, and absolute, both work.
  for (const std::string& ok_name : {std::string("sub/in.mocapses"), rec + "/abs-in.mocapses"}) {
    const auto reply = d.call("record start " + ok_name);
    ASSERT_TRUE(reply.value("ok", false)) << ok_name << ": " << reply.dump();
    EXPECT_TRUE(d.call("record stop").value("ok", false));
  }
  EXPECT_TRUE(fs::exists(rec + "/sub/in.mocapses"));
  EXPECT_TRUE(fs::exists(rec + "/abs-in.mocapses"));
  EXPECT_EQ(d.quit(), 0) << d.log_text();
}

TEST(Recordings, WithoutANameAFreshTakeNameIsPickedAndStopReportsWhatWasRecorded) {
  TwoSensorDaemon setup("fresh");
  auto& [dir, rig, port, d] = setup;
  ASSERT_TRUE(setup.ready_and_streaming()) << d.log_text();
  std::vector<std::string> files;
  for (int i = 0; i < 3; ++i) {  // within a second or two: the same base name, suffixed
    const auto start = d.call("record start");
    ASSERT_TRUE(start.value("ok", false)) << start.dump();
    const std::string file = start.value("file", "");
    EXPECT_TRUE(std::regex_search(file, std::regex(R"(/take-\d{8}-\d{6}(-\d+)?\.mocapses$)")))
        << file;
    for (const auto& f : files)
      EXPECT_NE(f, file);
    files.push_back(file);
    std::this_thread::sleep_for(300ms);
    const auto stop = d.call("record stop");
    ASSERT_TRUE(stop.value("ok", false)) << stop.dump();
    EXPECT_EQ(stop.value("file", ""), file);
    EXPECT_GT(stop.value("duration_s", 0.0), 0.2) << stop.dump();
    EXPECT_GT(stop.value("frames", 0ull), 0u) << stop.dump();
    EXPECT_GT(stop.value("samples", 0ull), 0u) << stop.dump();
    EXPECT_TRUE(stop.contains("drops")) << stop.dump();
    EXPECT_EQ(stop.value("bytes", 0ull), fs::file_size(file)) << stop.dump();
    EXPECT_EQ(stop.value("frames", 0ull), poses_in(file)) << stop.dump();
  }
  EXPECT_EQ(d.quit(), 0) << d.log_text();
}

TEST(Recordings, AutoStartAfterAKillNineKeepsTheCrashedTake) {
  TempDir dir;
  TwoSensorRig rig(dir);
  const std::string cfg =
      base_config(dir, free_tcp_port(), "auto_start = \"auto.mocapses\"\n") + rig.sensors_toml();
  uintmax_t crashed_size = 0;
  {
    Daemon d(dir, "auto1", cfg);
    ASSERT_TRUE(d.wait_ready(15s)) << d.log_text();
    ASSERT_TRUE(wait_until([&] { return both_streaming(d); }, 15s)) << d.log_text();
    std::this_thread::sleep_for(500ms);
    d.kill9();
    crashed_size = fs::file_size(dir.file("auto.mocapses"));
  }
  ASSERT_GT(crashed_size, 1000u);
  const std::string crashed = slurp_file(dir.file("auto.mocapses"));
  Daemon d(dir, "auto2", cfg);  // as systemd's Restart=on-failure would
  ASSERT_TRUE(d.wait_ready(15s)) << d.log_text();
  const std::string now = d.status().value("recording", "");
  EXPECT_EQ(fs::path(now).filename(), "auto-2.mocapses") << now;
  EXPECT_EQ(slurp_file(dir.file("auto.mocapses")), crashed);
  EXPECT_EQ(d.quit(), 0) << d.log_text();
  EXPECT_EQ(slurp_file(dir.file("auto.mocapses")), crashed);
  EXPECT_TRUE(fs::exists(dir.file("auto-2.mocapses")));
}

namespace {

/// `mocap export IN --csv OUT`: its exit code, stderr, and the number of frames in the CSV.
struct Exported {
  int code = -1;
  std::string err, csv;
  size_t frames = 0;
};
Exported export_csv(const TempDir& dir, const std::string& in, const std::string& tag) {
  Exported e;
  const std::string out = dir.file(tag + ".csv");
  const Result r = run_bin("mocap", {"export", in, "--csv", out});
  e.code = r.code;
  e.err = r.err;
  e.csv = slurp_file(out);
  const size_t rows = static_cast<size_t>(std::count(e.csv.begin(), e.csv.end(), '\n'));
  e.frames = rows > 0 ? (rows - 1) / 16 : 0;
  return e;
}

}  // namespace

TEST(Recordings, OneFlippedBitInARecordedSessionLosesAtMostItsBlock) {
  TwoSensorDaemon setup("flip");
  auto& [dir, rig, port, d] = setup;
  ASSERT_TRUE(setup.ready_and_streaming()) << d.log_text();
  ASSERT_TRUE(d.call("record start take.mocapses").value("ok", false));
  std::this_thread::sleep_for(1500ms);
  ASSERT_TRUE(d.call("record stop").value("ok", false));
  EXPECT_EQ(d.quit(), 0) << d.log_text();
  const std::string path = dir.file("take.mocapses");
  const Exported original = export_csv(dir, path, "original");
  ASSERT_EQ(original.code, 0) << original.err;
  ASSERT_GT(original.frames, 10u) << original.err;

  // The block holding the middle byte, from the intact file.
  const std::string bytes = slurp_file(path);
  const uint64_t mid = bytes.size() / 2;
  uint64_t block_begin = 0, block_end = 0;
  {
    SessionReader r;
    std::string err;
    ASSERT_TRUE(r.open(path, &err)) << err;
    SessionReader::Block b;
    while (r.next(b)) {
      if (b.offset <= mid && r.tail_offset() > mid) {
        block_begin = b.offset;
        block_end = r.tail_offset();
      }
    }
    ASSERT_EQ(r.end(), SessionReader::End::clean);
  }
  ASSERT_GT(block_end, block_begin);

  // A bit in the middle: that block alone is skipped and reported, exit status 3.
  {
    std::string damaged = bytes;
    damaged[mid] = static_cast<char>(damaged[mid] ^ 0x08);
    const std::string dpath = dir.file("mid.mocapses");
    { std::ofstream(dpath, std::ios::binary) << damaged; }
    SessionReader r;
    std::string err;
    ASSERT_TRUE(r.open(dpath, &err)) << err;
    SessionReader::Block b;
    while (r.next(b)) {
    }
    EXPECT_EQ(r.end(), SessionReader::End::corrupt);
    ASSERT_EQ(r.damaged().size(), 1u);
    EXPECT_EQ(r.damaged()[0].begin, block_begin);
    EXPECT_EQ(r.damaged()[0].end, block_end);
    // The time span lost: the blocks beside it (streams interleave, so either may be later).
    EXPECT_GT(r.damaged()[0].t_before_ns, 0);
    EXPECT_GT(r.damaged()[0].t_after_ns, 0);
    EXPECT_LT(std::abs(r.damaged()[0].t_after_ns - r.damaged()[0].t_before_ns), 500'000'000);
    const Exported e = export_csv(dir, dpath, "mid");
    EXPECT_EQ(e.code, 3) << e.err;
    EXPECT_GE(e.frames + 1, original.frames) << e.err;
    EXPECT_NE(e.err.find("damaged bytes " + std::to_string(block_begin) + "-" +
                         std::to_string(block_end)),
              std::string::npos)
        << e.err;
  }
  // A bit in the header: recovered from its copy, everything exported, exit status 0.
  for (const uint64_t at : {uint64_t{3}, uint64_t{17}, uint64_t{100}}) {
    std::string damaged = bytes;
    damaged[at] = static_cast<char>(damaged[at] ^ 0x10);
    const std::string hpath = dir.file("head.mocapses");
    { std::ofstream(hpath, std::ios::binary | std::ios::trunc) << damaged; }
    const Exported e = export_csv(dir, hpath, "head");
    EXPECT_EQ(e.code, 0) << at << ": " << e.err;
    EXPECT_EQ(e.csv, original.csv) << at;
    EXPECT_NE(e.err.find("read from its copy"), std::string::npos) << e.err;
  }
  std::printf(
      "[figures] bit flip at byte %llu of %zu: block %llu-%llu (%llu bytes) skipped, "
      "%zu of %zu frames exported; header bit flips: all %zu frames exported\n",
      static_cast<unsigned long long>(mid), bytes.size(),
      static_cast<unsigned long long>(block_begin), static_cast<unsigned long long>(block_end),
      static_cast<unsigned long long>(block_end - block_begin),
      export_csv(dir, dir.file("mid.mocapses"), "mid2").frames, original.frames, original.frames);
}

// recording.compression = "zstd" in the real mocapd: the take has compressed blocks, exports
// the same frames as it would uncompressed, and one flipped bit in the middle loses only the
// compressed block holding it (reported, exit status 3).
TEST(Recordings, ACompressedTakeExportsAndABitFlipLosesOnlyItsCompressedBlock) {
  TwoSensorDaemon setup("zstd", {}, "compression = \"zstd\"\n");
  auto& [dir, rig, port, d] = setup;
  ASSERT_TRUE(setup.ready_and_streaming()) << d.log_text();
  ASSERT_TRUE(d.call("record start take.mocapses").value("ok", false));
  std::this_thread::sleep_for(2000ms);
  const auto stop = d.call("record stop");
  ASSERT_TRUE(stop.value("ok", false)) << stop.dump();
  EXPECT_EQ(d.quit(), 0) << d.log_text();
  const std::string path = dir.file("take.mocapses");
  EXPECT_EQ(stop.value("bytes", uint64_t{0}), fs::file_size(path)) << stop.dump();
  const Exported original = export_csv(dir, path, "original");
  ASSERT_EQ(original.code, 0) << original.err;
  ASSERT_GT(original.frames, 10u) << original.err;
  EXPECT_EQ(poses_in(path), stop.value("frames", uint64_t{0}));

  // Which compressed blocks hold how many poses.
  const std::string bytes = slurp_file(path);
  std::map<uint64_t, int> poses_at;
  uint64_t compressed = 0;
  {
    SessionReader r;
    std::string err;
    ASSERT_TRUE(r.open(path, &err)) << err;
    SessionReader::Block b;
    while (r.next(b))
      if (b.type == session::BlockType::pose) poses_at[b.offset] += b.inner ? 1 : 0;
    EXPECT_EQ(r.end(), SessionReader::End::clean);
    compressed = r.compressed_blocks();
  }
  EXPECT_GT(compressed, 0u);

  const uint64_t mid = bytes.size() / 2;
  std::string damaged = bytes;
  damaged[mid] = static_cast<char>(damaged[mid] ^ 0x08);
  const std::string dpath = dir.file("mid.mocapses");
  { std::ofstream(dpath, std::ios::binary) << damaged; }
  SessionReader r;
  std::string err;
  ASSERT_TRUE(r.open(dpath, &err)) << err;
  SessionReader::Block b;
  while (r.next(b)) {
  }
  ASSERT_EQ(r.damaged().size(), 1u);
  const auto& range = r.damaged()[0];
  EXPECT_LE(range.begin, mid);
  EXPECT_GT(range.end, mid);
  EXPECT_LE(range.end - range.begin, 70'000u);  // one block at most
  const int lost_poses = poses_at.count(range.begin) ? poses_at[range.begin] : 1;
  const Exported e = export_csv(dir, dpath, "mid");
  EXPECT_EQ(e.code, 3) << e.err;
  EXPECT_GE(e.frames + static_cast<size_t>(lost_poses), original.frames) << e.err;
  EXPECT_GT(e.frames, 0u);
  std::printf(
      "[figures] zstd take: %zu bytes, %llu compressed blocks, %zu frames; bit flip at byte "
      "%llu: %llu bytes skipped (%d poses in them), %zu frames exported\n",
      bytes.size(), static_cast<unsigned long long>(compressed), original.frames,
      static_cast<unsigned long long>(mid),
      static_cast<unsigned long long>(range.end - range.begin), lost_poses, e.frames);
}
