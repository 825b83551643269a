// Session compression and clock blocks on real files: a zstd-compressed recording reads back
// block for block (and seeks into compressed blocks), is smaller, a damaged compressed block
// costs only the blocks inside it, uncompressed files read the same as before, and the wall
// clock recorded by the writer thread comes back from the reader; a full disk keeps every whole
// compressed block.
#include <gtest/gtest.h>
#include <sys/mount.h>
#include <time.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <thread>

#include "session_test_util.hpp"

using namespace mocap;
using namespace mocap::test;
namespace ses = mocap::session;

namespace {

constexpr int kPoses = 400;

SessionWriter::Options zstd_options() {
  SessionWriter::Options o;
  o.compression = SessionWriter::Options::Compression::zstd;
  o.compression_level = 3;
  return o;
}

/// kPoses x (pose, sample, raw), like a recording; returns the writer's final stats.
SessionWriter::Stats write_session(const std::string& path, SessionWriter::Options o) {
  std::string err;
  auto w = SessionWriter::create(path, make_header(), std::move(o), &err);
  EXPECT_TRUE(w) << err;
  if (!w) return {};
  for (int i = 0; i < kPoses; ++i) {
    EXPECT_TRUE(w->append_pose(make_pose(static_cast<uint64_t>(i))));
    EXPECT_TRUE(w->append_sample(make_sample(static_cast<uint32_t>(i))));
    const auto raw = make_raw(static_cast<uint32_t>(i), 40);
    EXPECT_TRUE(w->append_raw(static_cast<uint16_t>(i % 2), 77 + i, raw));
  }
  EXPECT_TRUE(w->close());
  return w->stats();
}

/// Which of the kPoses x 3 blocks were read, in order; false if one is wrong or out of order.
struct Readback {
  std::vector<bool> seen = std::vector<bool>(3 * kPoses, false);
  int count = 0;
  bool in_order = true;
};

Readback read_all(SessionReader& r) {
  Readback out;
  SessionReader::Block b;
  int last = -1;
  while (r.next(b)) {
    int k = -1;
    if (b.type == ses::BlockType::pose) {
      k = 3 * static_cast<int>(b.pose.frame);
      out.in_order &= same_pose(b.pose, make_pose(b.pose.frame));
    } else if (b.type == ses::BlockType::sample) {
      k = 3 * static_cast<int>(b.sample.seq) + 1;
      out.in_order &= same_sample(b.sample, make_sample(b.sample.seq));
    } else if (b.type == ses::BlockType::raw) {
      const auto i = static_cast<uint32_t>(b.t_host_ns - 77);
      k = 3 * static_cast<int>(i) + 2;
      out.in_order &= std::vector<uint8_t>(b.raw.begin(), b.raw.end()) == make_raw(i, 40);
    }
    if (k < 0 || k >= 3 * kPoses || k <= last) {
      out.in_order = false;
      continue;
    }
    last = k;
    out.seen[static_cast<std::size_t>(k)] = true;
    ++out.count;
  }
  return out;
}

}  // namespace

TEST(SessionCompression, RoundTripIsSmallerAndReadsBlockForBlock) {
  TempDir dir;
  const auto plain = write_session(dir.file("plain.mocapses"), {});
  const auto packed = write_session(dir.file("zstd.mocapses"), zstd_options());
  const auto plain_size = std::filesystem::file_size(dir.file("plain.mocapses"));
  const auto packed_size = std::filesystem::file_size(dir.file("zstd.mocapses"));
  EXPECT_EQ(packed.blocks_durable, 3u * kPoses);
  EXPECT_EQ(packed.bytes_durable, packed_size);
  EXPECT_EQ(plain.bytes_uncompressed, plain.bytes_blocks);
  EXPECT_EQ(packed.bytes_uncompressed, plain.bytes_uncompressed);
  EXPECT_LT(packed.bytes_blocks * 2, packed.bytes_uncompressed);  // these poses pack well
  EXPECT_LT(packed_size * 2, plain_size);

  SessionReader r;
  std::string err;
  ASSERT_TRUE(r.open(dir.file("zstd.mocapses"), &err)) << err;
  EXPECT_EQ(r.header(), make_header());
  const Readback got = read_all(r);
  EXPECT_EQ(got.count, 3 * kPoses);
  EXPECT_TRUE(got.in_order);
  EXPECT_EQ(r.end(), SessionReader::End::clean) << r.tail_reason();
  EXPECT_GT(r.compressed_blocks(), 0u);
  EXPECT_TRUE(r.damaged().empty());

  // Random access into a compressed block: seek to the 300th pose by its (offset, inner).
  SessionReader r2;
  ASSERT_TRUE(r2.open(dir.file("zstd.mocapses"), &err)) << err;
  SessionReader::Block b;
  uint64_t off = 0;
  uint32_t inner = 0;
  while (r2.next(b))
    if (b.type == ses::BlockType::pose && b.pose.frame == 300) {
      off = b.offset;
      inner = b.inner;
    }
  ASSERT_GT(inner, 0u);
  ASSERT_TRUE(r2.seek(off, inner));
  ASSERT_TRUE(r2.next(b));
  ASSERT_EQ(b.type, ses::BlockType::pose);
  EXPECT_EQ(b.pose.frame, 300u);
  ASSERT_TRUE(r2.next(b));
  EXPECT_EQ(b.type, ses::BlockType::sample);
  EXPECT_EQ(b.sample.seq, 300u);
}

TEST(SessionCompression, ADamagedCompressedBlockLosesOnlyTheBlocksInsideIt) {
  TempDir dir;
  const std::string path = dir.file("zstd.mocapses");
  write_session(path, zstd_options());
  const auto intact = slurp(path);
  // Where the compressed blocks are (the first one's range).
  SessionReader probe;
  std::string err;
  ASSERT_TRUE(probe.open(path, &err)) << err;
  SessionReader::Block b;
  std::vector<uint64_t> groups;
  while (probe.next(b))
    if (b.inner && (groups.empty() || groups.back() != b.offset)) groups.push_back(b.offset);
  ASSERT_GE(groups.size(), 3u);
  for (const double where : {0.1, 0.5, 0.9}) {  // inside the 2nd compressed block
    auto bytes = intact;
    const uint64_t at = groups[1] + static_cast<uint64_t>(where * (groups[2] - groups[1]));
    bytes[at] ^= 0x10;
    SessionReader r;
    ASSERT_TRUE(r.open_bytes(bytes, &err)) << err;
    const Readback got = read_all(r);
    EXPECT_TRUE(got.in_order);
    EXPECT_EQ(r.end(), SessionReader::End::corrupt);
    ASSERT_EQ(r.damaged().size(), 1u) << at;
    EXPECT_EQ(r.damaged()[0].begin, groups[1]);
    EXPECT_EQ(r.damaged()[0].end, groups[2]);
    EXPECT_GT(r.damaged()[0].t_before_ns, 0);
    EXPECT_GE(r.damaged()[0].t_after_ns, 0);
    // Everything outside the damaged block is read: the blocks of the 1st and 3rd groups too.
    SessionReader whole;
    ASSERT_TRUE(whole.open_bytes(intact, &err));
    int lost = 0;
    while (whole.next(b))
      lost += b.offset == groups[1];
    EXPECT_EQ(got.count, 3 * kPoses - lost);
    EXPECT_GT(lost, 0);
  }
}

TEST(SessionCompression, UncompressedFilesHaveNoCompressedBlocksAndReadAsBefore) {
  TempDir dir;
  const std::string path = dir.file("plain.mocapses");
  write_session(path, {});
  SessionReader r;
  std::string err;
  ASSERT_TRUE(r.open(path, &err)) << err;
  const Readback got = read_all(r);
  EXPECT_EQ(got.count, 3 * kPoses);
  EXPECT_TRUE(got.in_order);
  EXPECT_EQ(r.compressed_blocks(), 0u);
  EXPECT_EQ(r.end(), SessionReader::End::clean);
  // The golden session recorded before compression and clock blocks existed (and named .mcap).
  SessionReader old;
  ASSERT_TRUE(old.open(std::string(MOCAP_SOURCE_DIR) + "/tests/data/demo_direct_50hz.mcap", &err))
      << err;
  SessionReader::Block b;
  int samples = 0;
  while (old.next(b))
    samples += b.type == ses::BlockType::sample;
  EXPECT_GT(samples, 100);
  EXPECT_EQ(old.end(), SessionReader::End::clean) << old.tail_reason();
  EXPECT_EQ(old.compressed_blocks(), 0u);
}

TEST(SessionCompression, TheWallClockBesideTheMonotonicOneComesBackFromTheReader) {
  TempDir dir;
  const std::string path = dir.file("clock.mocapses");
  // make_header()'s start times are made up: realtime - monotonic there is far from the real
  // offset, so the writer records the real one in a clock block (and at least every 1 ms).
  const session::SessionHeader h = make_header();
  SessionWriter::Options o = zstd_options();
  o.clock_interval_ms = 1;
  std::string err;
  auto w = SessionWriter::create(path, h, o, &err);
  ASSERT_TRUE(w) << err;
  for (int i = 0; i < 5; ++i) {
    ASSERT_TRUE(w->append_pose(make_pose(static_cast<uint64_t>(i))));
    std::this_thread::sleep_for(std::chrono::milliseconds(60));  // a writer round in between
  }
  ASSERT_TRUE(w->close());
  EXPECT_EQ(w->stats().blocks_durable, 5u);  // clock blocks are not counted as appended

  timespec rt{}, mt{};
  ::clock_gettime(CLOCK_REALTIME, &rt);
  ::clock_gettime(CLOCK_MONOTONIC, &mt);
  const int64_t offset_now = (rt.tv_sec - mt.tv_sec) * 1'000'000'000ll + (rt.tv_nsec - mt.tv_nsec);

  SessionReader r;
  ASSERT_TRUE(r.open(path, &err)) << err;
  EXPECT_EQ(r.unix_offset_ns(), h.t_start_unix_ns - h.t_start_host_ns);  // from the header
  SessionReader::Block b;
  int poses = 0;
  while (r.next(b)) {
    EXPECT_NE(b.type, ses::BlockType::clock);  // absorbed by the reader
    ++poses;
  }
  EXPECT_EQ(poses, 5);
  EXPECT_EQ(r.end(), SessionReader::End::clean);
  EXPECT_LT(std::llabs(r.unix_offset_ns() - offset_now), 50'000'000ll);
}

// A full disk while compressing: the recording stops with the error, and every compressed block
// written before it reads back whole (the torn one cut off), frames in order from the first.
TEST(SessionCompression, DiskFullMidRecordingKeepsEveryWholeCompressedBlock) {
  if (const std::string why = test_mounts_unavailable(); !why.empty())
    GTEST_SKIP() << "needs root and a private mount namespace for a 64 KiB tmpfs: " << why;
  TempDir dir;
  ASSERT_EQ(mount_small_tmpfs(dir.path()), "");
  const std::string path = dir.file("full.mocapses");
  std::string err;
  auto w = SessionWriter::create(path, make_header(), zstd_options(), &err);
  ASSERT_TRUE(w) << err;
  int i = 0;
  for (; i < 2'000'000 && w->stats().state == SessionWriter::State::recording; ++i) {
    PoseFrame f = make_pose(static_cast<uint64_t>(i));
    f.q_earth_segment[0][1] = static_cast<float>(i % 977) * 1e-3f;  // less compressible
    w->append_pose(f);
    if (i % 50 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  const auto st = w->stats();
  ASSERT_EQ(st.state, SessionWriter::State::failed) << i;
  EXPECT_NE(st.error.find("No space left on device"), std::string::npos) << st.error;
  EXPECT_FALSE(w->close());
  EXPECT_GT(st.blocks_durable, 100u);
  EXPECT_LT(st.bytes_blocks, st.bytes_uncompressed);
  SessionReader r;
  ASSERT_TRUE(r.open(path, &err)) << err;
  SessionReader::Block b;
  uint64_t n = 0;
  while (r.next(b)) {
    ASSERT_EQ(b.pose.frame, n);
    ++n;
  }
  EXPECT_EQ(n, st.blocks_durable);
  EXPECT_EQ(r.end(), SessionReader::End::clean) << r.tail_reason();
  EXPECT_EQ(std::filesystem::file_size(path), st.bytes_durable);
  ::umount2(dir.path().c_str(), MNT_DETACH);
}
