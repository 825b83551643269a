// Storage faults against the real mocapd recording live pty sensors: kill -9 at random moments
// (the file always reads back, up to its last flush, with nothing corrupt), a disk that fills
// up mid-recording (a 256 KiB tmpfs), /dev/full, a read-only file system and a missing
// directory: a clear error, the pipeline keeps running, nothing recorded before is lost.
#include <gtest/gtest.h>
#include <sched.h>
#include <sys/mount.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <map>
#include <random>
#include <thread>

#include "harness.hpp"
#include "mocap/core/time.hpp"
#include "mocap/session/session_reader.hpp"

using namespace mocap;
using namespace mocap::reliability;
using mocap::SessionReader;
using namespace std::chrono_literals;

namespace {

struct ReadBack {
  bool opened = false;
  std::string error;
  SessionReader::End end = SessionReader::End::not_reached;
  std::string tail_reason;
  std::map<uint16_t, uint64_t> samples;  ///< per sensor id
  uint64_t poses = 0, raw = 0;
  bool samples_in_order = true, poses_in_order = true;
  int64_t last_t_ns = 0;  ///< host time of the newest sample
};

ReadBack read_back(const std::string& path) {
  ReadBack rb;
  SessionReader r;
  rb.opened = r.open(path, &rb.error);
  if (!rb.opened) return rb;
  SessionReader::Block b;
  std::map<uint16_t, int64_t> last_t;
  int64_t last_frame = -1;
  while (r.next(b)) {
    switch (b.type) {
      case session::BlockType::sample: {
        auto& lt = last_t[b.sample.sensor_id];
        if (b.sample.t_host_ns < lt) rb.samples_in_order = false;
        lt = b.sample.t_host_ns;
        rb.last_t_ns = std::max(rb.last_t_ns, b.sample.t_host_ns);
        ++rb.samples[b.sample.sensor_id];
        break;
      }
      case session::BlockType::pose:
        if (static_cast<int64_t>(b.pose.frame) <= last_frame) rb.poses_in_order = false;
        last_frame = static_cast<int64_t>(b.pose.frame);
        ++rb.poses;
        break;
      default:
        ++rb.raw;
        break;
    }
  }
  rb.end = r.end();
  rb.tail_reason = r.tail_reason();
  return rb;
}

/// Two healthy pty sensors feeding whichever daemon a test starts.

bool private_mounts(std::string& why) {
  if (::geteuid() != 0) {
    why = "not root";
    return false;
  }
  if (::unshare(CLONE_NEWNS) != 0 || ::mount(nullptr, "/", nullptr, MS_REC | MS_PRIVATE, nullptr)) {
    why = std::string("private mount namespace: ") + std::strerror(errno);
    return false;
  }
  return true;
}

}  // namespace

TEST(StorageFaults, KillNineWhileRecordingAlwaysLeavesAReadableFile) {
  TempDir dir;
  TwoSensorRig rig(dir);
  std::mt19937 rng(20261122);
  std::uniform_int_distribution<int> kill_after_ms(200, 1500);
  constexpr int kRounds = 6;
  double worst_loss_ms = 0;
  uint64_t total_samples = 0;
  int torn = 0;
  for (int round = 0; round < kRounds; ++round) {
    const std::string file = "kill" + std::to_string(round) + ".mocap";
    const int port = free_tcp_port();
    Daemon d(dir, "kill" + std::to_string(round),
             base_config(dir, port, "auto_start = \"" + file + "\"\n") + rig.sensors_toml());
    ASSERT_TRUE(d.wait_ready(15s)) << d.log_text();
    ASSERT_TRUE(wait_until([&] { return both_streaming(d); }, 15s)) << d.log_text();
    std::this_thread::sleep_for(std::chrono::milliseconds(kill_after_ms(rng)));
    const int64_t t_kill = monotonic_ns();
    d.kill9();
    ReadBack rb = read_back(dir.file(file));
    ASSERT_TRUE(rb.opened) << rb.error;
    EXPECT_NE(rb.end, SessionReader::End::corrupt) << "round " << round << ": " << rb.tail_reason;
    if (rb.end == SessionReader::End::torn) ++torn;
    EXPECT_TRUE(rb.samples_in_order);
    EXPECT_TRUE(rb.poses_in_order);
    EXPECT_GT(rb.samples[0], 0u) << "round " << round;
    EXPECT_GT(rb.samples[1], 0u) << "round " << round;
    EXPECT_GT(rb.poses, 0u);
    total_samples += rb.samples[0] + rb.samples[1];
    worst_loss_ms = std::max(worst_loss_ms, ns_to_s(t_kill - rb.last_t_ns) * 1e3);
  }
  std::printf(
      "[figures] kill -9 x%d: every file readable, 0 corrupt, %d torn tails, %llu "
      "samples recovered, worst gap between the kill and the last durable sample %.0f ms\n",
      kRounds, torn, static_cast<unsigned long long>(total_samples), worst_loss_ms);
}

TEST(StorageFaults, DiskFullMidRecordingStopsTheRecordingOnlyAndKeepsWhatWasWritten) {
  std::string why;
  if (!private_mounts(why)) GTEST_SKIP() << "needs root for a small tmpfs: " << why;
  TwoSensorDaemon setup("full");
  auto& [dir, rig, port, d] = setup;
  const std::string small = dir.file("small");
  ASSERT_EQ(::mkdir(small.c_str(), 0755), 0);
  ASSERT_EQ(::mount("tmpfs", small.c_str(), "tmpfs", 0, "size=256k"), 0) << std::strerror(errno);
  ASSERT_TRUE(setup.ready_and_streaming()) << d.log_text();
  const std::string path = small + "/full.mocap";
  const auto reply = d.call("record start " + path);
  ASSERT_TRUE(reply.value("ok", false)) << reply.dump();
  // Raw bytes + samples + poses fill 256 KiB within seconds; the daemon notices and stops.
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_TRUE(wait_until([&] { return d.status().value("recording", "x").empty(); }, 60s))
      << d.status().dump();
  const double fill_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::string log = d.log_text();
  EXPECT_NE(log.find("No space left on device"), std::string::npos) << log;
  EXPECT_NE(log.find(path), std::string::npos) << log;
  // The pipeline did not stop: frames advance, both sensors stream, stream unaffected.
  const auto s1 = d.status();
  std::this_thread::sleep_for(400ms);
  const auto s2 = d.status();
  EXPECT_GT(s2.value("frame", 0ull), s1.value("frame", 0ull));
  EXPECT_TRUE(both_streaming(d));
  // Everything before the failure reads back.
  ReadBack rb = read_back(path);
  ASSERT_TRUE(rb.opened) << rb.error;
  EXPECT_NE(rb.end, SessionReader::End::corrupt) << rb.tail_reason;
  EXPECT_GT(rb.samples.at(0), 10u);
  EXPECT_GT(rb.poses, 10u);
  // A new recording elsewhere works at once.
  const auto again = d.call("record start again.mocap");
  EXPECT_TRUE(again.value("ok", false)) << again.dump();
  std::this_thread::sleep_for(300ms);
  EXPECT_TRUE(d.call("record stop").value("ok", false));
  EXPECT_GT(read_back(dir.file("again.mocap")).samples[0], 0u);
  std::printf(
      "[figures] disk full: 256 KiB filled after %.1f s, %llu+%llu samples and %llu "
      "poses kept, end %s\n",
      fill_s, static_cast<unsigned long long>(rb.samples.at(0)),
      static_cast<unsigned long long>(rb.samples.count(1) ? rb.samples.at(1) : 0),
      static_cast<unsigned long long>(rb.poses),
      rb.end == SessionReader::End::clean ? "clean" : "torn");
  EXPECT_EQ(d.quit(), 0) << d.log_text();
  ::umount2(small.c_str(), MNT_DETACH);
}

TEST(StorageFaults, UnwritableTargetsGetAClearErrorAndThePipelineContinues) {
  std::string why;
  const bool mounts = private_mounts(why);
  TwoSensorDaemon setup("ro");
  auto& [dir, rig, port, d] = setup;
  const std::string ro = dir.file("ro");
  ASSERT_EQ(::mkdir(ro.c_str(), 0755), 0);
  if (mounts) {
    ASSERT_EQ(::mount("tmpfs", ro.c_str(), "tmpfs", MS_RDONLY, "size=64k"), 0)
        << std::strerror(errno);
  }
  ASSERT_TRUE(setup.ready_and_streaming()) << d.log_text();

  struct Case {
    std::string target, expect;
  };
  std::vector<Case> cases{{"/dev/full", "/dev/full"},
                          {dir.file("missing/dir/x.mocap"), "missing/dir/x.mocap"}};
  if (mounts) cases.push_back({ro + "/x.mocap", "Read-only file system"});
  for (const auto& c : cases) {
    const uint64_t frame_before = d.status().value("frame", 0ull);
    const auto reply = d.call("record start " + c.target);
    EXPECT_FALSE(reply.value("ok", true)) << c.target << ": " << reply.dump();
    EXPECT_NE(reply.value("error", "").find(c.expect), std::string::npos) << reply.dump();
    EXPECT_TRUE(d.status().value("recording", "x").empty());
    EXPECT_TRUE(
        wait_until([&] { return d.status().value("frame", 0ull) > frame_before + 10; }, 5s));
    EXPECT_TRUE(both_streaming(d));
  }
  if (!mounts) std::printf("read-only mount case skipped: %s\n", why.c_str());
  EXPECT_EQ(d.quit(), 0) << d.log_text();
  if (mounts) ::umount2(ro.c_str(), MNT_DETACH);
}
