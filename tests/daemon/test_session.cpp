// Session recording tests on real files: round trip of every block type, torn tails at every
// byte, corruption, version/limit rejection, buffer overflow accounting (through a real FIFO
// that stalls the writer thread), /dev/full, a full tmpfs, a read-only mount, and EACCES.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sched.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <thread>

#include "session_test_util.hpp"

using namespace mocap;
using namespace mocap::test;
namespace ses = mocap::session;

namespace {

/// Writes `poses` poses, each followed by one sample and one raw chunk; returns the file bytes.
std::vector<uint8_t> write_small_session(const std::string& path, int poses) {
  std::string err;
  auto w = SessionWriter::create(path, make_header(), {}, &err);
  EXPECT_TRUE(w) << err;
  if (!w) return {};
  for (int i = 0; i < poses; ++i) {
    EXPECT_TRUE(w->append_pose(make_pose(static_cast<uint64_t>(i))));
    EXPECT_TRUE(w->append_sample(make_sample(static_cast<uint32_t>(i))));
    const auto raw = make_raw(static_cast<uint32_t>(i), 5 + static_cast<std::size_t>(i));
    EXPECT_TRUE(w->append_raw(static_cast<uint16_t>(i % 2), 77 + i, raw));
  }
  EXPECT_TRUE(w->close());
  return slurp(path);
}

struct Counted {
  int blocks = 0;
  bool in_order = true;
};

/// Reads every block and checks it is the one write_small_session wrote at that position.
Counted read_and_check(SessionReader& r) {
  Counted c;
  SessionReader::Block b;
  while (r.next(b)) {
    const int i = c.blocks / 3;
    switch (c.blocks % 3) {
      case 0:
        c.in_order &= b.type == ses::BlockType::pose && same_pose(b.pose, make_pose(i));
        break;
      case 1:
        c.in_order &= b.type == ses::BlockType::sample &&
                      same_sample(b.sample, make_sample(static_cast<uint32_t>(i)));
        break;
      case 2: {
        const auto raw = make_raw(static_cast<uint32_t>(i), 5 + static_cast<std::size_t>(i));
        c.in_order &= b.type == ses::BlockType::raw && b.device_index == i % 2 &&
                      b.t_host_ns == 77 + i &&
                      std::vector<uint8_t>(b.raw.begin(), b.raw.end()) == raw;
        break;
      }
    }
    ++c.blocks;
  }
  return c;
}

}  // namespace

TEST(Session, RoundTripOfEveryBlockType) {
  TempDir dir;
  const std::string path = dir.file("a.mocap");
  std::string err;
  auto w = SessionWriter::create(path, make_header(), {}, &err);
  ASSERT_TRUE(w) << err;
  const auto big = make_raw(9, 150'000);  // becomes 3 raw blocks of <= 64 KiB
  ASSERT_TRUE(w->append_raw(3, 42, big));
  PoseFrame full = make_pose(1, kMaxSensors);
  ASSERT_TRUE(w->append_pose(full));
  for (uint32_t i = 0; i < 100; ++i)
    ASSERT_TRUE(w->append_sample(make_sample(i)));
  ASSERT_TRUE(w->close());
  const auto st = w->stats();
  EXPECT_EQ(st.state, SessionWriter::State::closed);
  EXPECT_EQ(st.blocks_appended, 104u);
  EXPECT_EQ(st.blocks_durable, 104u);
  EXPECT_EQ(st.blocks_dropped, 0u);
  EXPECT_EQ(st.bytes_durable, std::filesystem::file_size(path));

  SessionReader r;
  ASSERT_TRUE(r.open(path, &err)) << err;
  EXPECT_EQ(r.header(), make_header());
  SessionReader::Block b;
  std::vector<uint8_t> raw;
  for (int k = 0; k < 3; ++k) {
    ASSERT_TRUE(r.next(b));
    ASSERT_EQ(b.type, ses::BlockType::raw);
    EXPECT_EQ(b.device_index, 3);
    EXPECT_EQ(b.t_host_ns, 42);
    raw.insert(raw.end(), b.raw.begin(), b.raw.end());
  }
  EXPECT_EQ(raw, big);
  ASSERT_TRUE(r.next(b));
  ASSERT_EQ(b.type, ses::BlockType::pose);
  EXPECT_TRUE(same_pose(b.pose, full));
  for (uint32_t i = 0; i < 100; ++i) {
    ASSERT_TRUE(r.next(b));
    ASSERT_EQ(b.type, ses::BlockType::sample);
    EXPECT_TRUE(same_sample(b.sample, make_sample(i))) << i;
  }
  EXPECT_FALSE(r.next(b));
  EXPECT_EQ(r.end(), SessionReader::End::clean);
  EXPECT_EQ(r.tail_offset(), std::filesystem::file_size(path));
  EXPECT_EQ(r.ignored_bytes(), 0u);
}

TEST(Session, TruncationAtEveryByteKeepsTheWholeBlocksBefore) {
  TempDir dir;
  const auto bytes = write_small_session(dir.file("t.mocap"), 4);
  ASSERT_FALSE(bytes.empty());
  // Block boundaries from a full read.
  SessionReader full;
  std::string err;
  ASSERT_TRUE(full.open_bytes(bytes, &err)) << err;
  std::vector<uint64_t> ends;
  const uint64_t header_end = full.tail_offset();
  SessionReader::Block b;
  while (full.next(b))
    ends.push_back(full.tail_offset());
  ASSERT_EQ(ends.size(), 12u);
  for (std::size_t cut = header_end; cut <= bytes.size(); ++cut) {
    SessionReader r;
    ASSERT_TRUE(r.open_bytes({bytes.data(), cut}, &err)) << cut << ": " << err;
    const Counted c = read_and_check(r);
    const auto whole =
        std::count_if(ends.begin(), ends.end(), [&](uint64_t e) { return e <= cut; });
    ASSERT_EQ(c.blocks, whole) << "cut at " << cut;
    ASSERT_TRUE(c.in_order);
    const bool boundary =
        cut == header_end || std::find(ends.begin(), ends.end(), cut) != ends.end();
    ASSERT_EQ(r.end(), boundary ? SessionReader::End::clean : SessionReader::End::torn) << cut;
    ASSERT_EQ(r.tail_offset(), whole ? ends[whole - 1] : header_end);
  }
  // Cuts inside the header are refused with a message, never a crash; cuts inside its copy
  // (header_copy blocks) keep the header and no block.
  const std::size_t primary = 24 + ses::get_u32(bytes.data() + 16);
  for (std::size_t cut = 0; cut < header_end; ++cut) {
    SessionReader r;
    EXPECT_EQ(r.open_bytes({bytes.data(), cut}, &err), cut >= primary) << cut;
    if (cut >= primary) {
      EXPECT_FALSE(r.next(b));
    }
  }
}

TEST(Session, ZeroFilledTailAfterPowerLossIsTorn) {
  TempDir dir;
  auto bytes = write_small_session(dir.file("z.mocap"), 3);
  const std::size_t good = bytes.size();
  bytes.resize(good + 4096, 0);
  SessionReader r;
  std::string err;
  ASSERT_TRUE(r.open_bytes(bytes, &err)) << err;
  const Counted c = read_and_check(r);
  EXPECT_EQ(c.blocks, 9);
  EXPECT_TRUE(c.in_order);
  EXPECT_EQ(r.end(), SessionReader::End::torn);
  EXPECT_EQ(r.tail_offset(), good);
  EXPECT_EQ(r.ignored_bytes(), 4096u);
}

TEST(Session, CorruptBlockInTheMiddleIsSkippedAndReported) {
  TempDir dir;
  auto bytes = write_small_session(dir.file("c.mocap"), 4);
  SessionReader probe;
  std::string err;
  ASSERT_TRUE(probe.open_bytes(bytes, &err));
  SessionReader::Block b;
  for (int i = 0; i < 5; ++i)
    ASSERT_TRUE(probe.next(b));
  const uint64_t fifth_end = probe.tail_offset();
  const int64_t fifth_t = b.sample.t_host_ns;
  ASSERT_TRUE(probe.next(b));
  const uint64_t sixth_end = probe.tail_offset();
  ASSERT_TRUE(probe.next(b));
  const int64_t seventh_t = b.pose.t_ns;
  bytes[fifth_end + 20] ^= 0x40;  // inside the sixth block's payload
  SessionReader r;
  ASSERT_TRUE(r.open_bytes(bytes, &err));
  int blocks = 0;
  while (r.next(b))
    ++blocks;
  EXPECT_EQ(blocks, 11);  // all but the sixth
  EXPECT_EQ(r.end(), SessionReader::End::corrupt);
  EXPECT_EQ(r.tail_offset(), bytes.size());
  EXPECT_EQ(r.ignored_bytes(), 0u);
  ASSERT_EQ(r.damaged().size(), 1u);
  const auto& d = r.damaged()[0];
  EXPECT_EQ(d.begin, fifth_end);
  EXPECT_EQ(d.end, sixth_end);
  EXPECT_EQ(d.t_before_ns, fifth_t);
  EXPECT_EQ(d.t_after_ns, seventh_t);
  EXPECT_EQ(r.damaged_bytes(), sixth_end - fifth_end);
  EXPECT_NE(r.tail_reason().find("checksum"), std::string::npos) << r.tail_reason();
  EXPECT_NE(r.tail_reason().find(std::to_string(fifth_end)), std::string::npos);
}

/// (type, index) of every block of a write_small_session file, in order.
std::vector<std::pair<int, int64_t>> block_ids(SessionReader& r) {
  std::vector<std::pair<int, int64_t>> out;
  SessionReader::Block b;
  while (r.next(b)) {
    const int t = static_cast<int>(b.type);
    out.emplace_back(t, t == 1   ? b.t_host_ns
                        : t == 2 ? b.sample.seq
                                 : static_cast<int64_t>(b.pose.frame));
  }
  return out;
}

TEST(Session, OneFlippedBitAnywhereInTheBlocksLosesAtMostItsBlock) {
  TempDir dir;
  const auto good = write_small_session(dir.file("f.mocap"), 6);
  SessionReader full;
  std::string err;
  ASSERT_TRUE(full.open_bytes(good, &err));
  const uint64_t first_block = full.tail_offset();
  const auto all = block_ids(full);
  ASSERT_EQ(all.size(), 18u);
  for (std::size_t at = first_block; at < good.size(); ++at) {
    auto bytes = good;
    bytes[at] ^= static_cast<uint8_t>(1u << (at % 8));
    SessionReader r;
    ASSERT_TRUE(r.open_bytes(bytes, &err)) << at << ": " << err;
    const auto got = block_ids(r);
    ASSERT_GE(got.size(), all.size() - 1) << "bit flipped at " << at;
    // What was read is the original sequence with at most one block missing.
    std::size_t j = 0, missing = 0;
    for (std::size_t i = 0; i < all.size(); ++i) {
      if (j < got.size() && got[j] == all[i])
        ++j;
      else
        ++missing;
    }
    ASSERT_EQ(j, got.size()) << "bit flipped at " << at;
    ASSERT_LE(missing, 1u) << at;
    if (missing) {
      ASSERT_NE(r.end(), SessionReader::End::clean) << at;
      ASSERT_FALSE(r.tail_reason().empty()) << at;
    }
  }
}

TEST(Session, OneFlippedBitInTheHeaderIsRecoveredFromItsCopy) {
  TempDir dir;
  const auto good = write_small_session(dir.file("h.mocap"), 3);
  const std::size_t primary = 24 + ses::get_u32(good.data() + 16);
  SessionReader full;
  std::string err;
  ASSERT_TRUE(full.open_bytes(good, &err));
  EXPECT_FALSE(full.header_recovered());
  const auto all = block_ids(full);
  for (std::size_t at = 0; at < primary; ++at) {
    auto bytes = good;
    bytes[at] ^= static_cast<uint8_t>(1u << (at % 8));
    SessionReader r;
    ASSERT_TRUE(r.open_bytes(bytes, &err)) << at << ": " << err;
    EXPECT_TRUE(r.header_recovered()) << at;
    EXPECT_FALSE(r.header_damage().empty()) << at;
    EXPECT_EQ(r.header(), make_header()) << at;
    EXPECT_EQ(block_ids(r), all) << at;
    EXPECT_EQ(r.end(), SessionReader::End::clean) << at;
  }
}

TEST(Session, ForeignFilesVersionsAndOversizedLengthsAreRejectedClearly) {
  TempDir dir;
  const auto good = write_small_session(dir.file("v.mocap"), 1);
  std::string err;
  SessionReader r;
  auto expect_error = [&](std::vector<uint8_t> bytes, const std::string& needle) {
    SessionReader rr;
    std::string e;
    EXPECT_FALSE(rr.open_bytes(bytes, &e));
    EXPECT_NE(e.find(needle), std::string::npos) << "got: " << e;
  };
  // The header alone (as version-1 files written before the header copy existed, or a file
  // whose copy is damaged too): each problem is named.
  const std::vector<uint8_t> header_only(good.begin(),
                                         good.begin() + 24 + ses::get_u32(good.data() + 16));
  auto v2 = header_only;
  ses::put_u32(v2.data() + 8, 2);
  expect_error(v2, "version 2 is not supported");
  auto be = header_only;
  ses::put_u32(be.data() + 12, 0x04030201);
  expect_error(be, "byte-order");
  auto huge = header_only;
  ses::put_u32(huge.data() + 16, 0xffffffffu);
  expect_error(huge, "exceeds the 4 MiB limit");
  auto bad_crc = header_only;
  bad_crc[30] ^= 1;
  expect_error(bad_crc, "checksum");
  {  // A file without the copy (older writers) still reads.
    SessionReader old;
    ASSERT_TRUE(old.open_bytes(header_only, &err)) << err;
    SessionReader::Block blk;
    EXPECT_FALSE(old.next(blk));
    EXPECT_EQ(old.end(), SessionReader::End::clean);
  }
  expect_error({'h', 'e', 'l', 'l', 'o'}, "not a mocap session file");
  EXPECT_FALSE(r.open(dir.file("missing.mocap"), &err));
  EXPECT_NE(err.find("missing.mocap"), std::string::npos);

  // A block length field far beyond the limit is refused before any allocation.
  ASSERT_TRUE(r.open_bytes(good, &err));
  const uint64_t first_block = r.tail_offset();
  auto long_block = good;
  ses::put_u32(long_block.data() + first_block + 4, 0x7fffffffu);
  SessionReader r2;
  ASSERT_TRUE(r2.open_bytes(long_block, &err));
  SessionReader::Block b;
  int after = 0;
  while (r2.next(b))
    ++after;
  EXPECT_EQ(after, 2);  // the sample and raw blocks after it
  EXPECT_EQ(r2.end(), SessionReader::End::corrupt);
  EXPECT_NE(r2.tail_reason().find("exceeds the limit"), std::string::npos);
  ASSERT_EQ(r2.damaged().size(), 1u);
  EXPECT_EQ(r2.damaged()[0].begin, first_block);

  // Over-long header fields are refused by the writer too.
  auto h = make_header();
  h.sensors[0].name.assign(300, 'x');
  EXPECT_FALSE(SessionWriter::create(dir.file("h.mocap"), h, {}, &err));
  EXPECT_NE(err.find("255"), std::string::npos) << err;
}

TEST(Session, FullBufferDropsAndCountsWithoutBlockingTheCaller) {
  // A FIFO whose reader stops reading: the writer thread blocks in write(), the ring fills,
  // further appends are refused at once and counted (the test would hang if they blocked).
  TempDir dir;
  const std::string fifo = dir.file("fifo");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::atomic<bool> drain{false};
  std::vector<uint8_t> received;
  std::thread reader([&] {
    const int fd = ::open(fifo.c_str(), O_RDONLY);
    uint8_t buf[4096];
    // Read only the first bytes (the header), then stall until told to drain.
    ssize_t n = ::read(fd, buf, sizeof buf);
    if (n > 0) received.insert(received.end(), buf, buf + n);
    while (!drain)
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    while ((n = ::read(fd, buf, sizeof buf)) > 0)
      received.insert(received.end(), buf, buf + n);
    ::close(fd);
  });
  std::string err;
  SessionWriter::Options opt;
  opt.buffer_bytes = 1;  // raised to the minimum (4 maximal blocks, about 256 KiB)
  auto w = SessionWriter::create(fifo, make_header(), opt, &err);
  ASSERT_TRUE(w) << err;
  constexpr int kPoses = 2000;  // about 1 MB of poses
  int accepted = 0;
  for (int i = 0; i < kPoses; ++i)
    accepted += w->append_pose(make_pose(i)) ? 1 : 0;
  auto st = w->stats();
  EXPECT_EQ(st.blocks_appended, static_cast<uint64_t>(accepted));
  EXPECT_EQ(st.blocks_appended + st.blocks_dropped, static_cast<uint64_t>(kPoses));
  EXPECT_GT(st.blocks_dropped, 0u);
  EXPECT_GT(st.buffer_high_water, 0u);
  drain = true;
  EXPECT_TRUE(w->close());
  reader.join();
  st = w->stats();
  EXPECT_EQ(st.blocks_durable, static_cast<uint64_t>(accepted));
  SessionReader r;
  ASSERT_TRUE(r.open_bytes(received, &err)) << err;
  SessionReader::Block b;
  int n = 0;
  int64_t prev = -1;
  while (r.next(b)) {
    ASSERT_EQ(b.type, ses::BlockType::pose);
    EXPECT_GT(static_cast<int64_t>(b.pose.frame), prev);
    EXPECT_TRUE(same_pose(b.pose, make_pose(b.pose.frame)));
    prev = static_cast<int64_t>(b.pose.frame);
    ++n;
  }
  EXPECT_EQ(n, accepted);
  EXPECT_EQ(r.end(), SessionReader::End::clean);
}

TEST(Session, DevFullRefusesTheRecordingWithAClearError) {
  std::string err;
  auto w = SessionWriter::create("/dev/full", make_header(), {}, &err);
  EXPECT_FALSE(w);
  EXPECT_NE(err.find("/dev/full"), std::string::npos) << err;
  EXPECT_NE(err.find("disk full"), std::string::npos) << err;
}

TEST(Session, DiskFullMidRecordingStopsCleanlyAndKeepsEverythingBefore) {
  if (const std::string why = test_mounts_unavailable(); !why.empty())
    GTEST_SKIP() << "needs root and a private mount namespace for a 64 KiB tmpfs: " << why;
  TempDir dir;
  ASSERT_EQ(mount_small_tmpfs(dir.path()), "");
  const std::string path = dir.file("full.mocap");
  std::atomic<int> callbacks{0};
  std::string message;
  SessionWriter::Options opt;
  opt.on_error = [&](const std::string& m) {
    message = m;
    ++callbacks;
  };
  std::string err;
  auto w = SessionWriter::create(path, make_header(), opt, &err);
  ASSERT_TRUE(w) << err;
  // Keep recording like the pipeline would until the writer reports the failure.
  int i = 0;
  for (; i < 100000 && w->stats().state == SessionWriter::State::recording; ++i) {
    w->append_pose(make_pose(static_cast<uint64_t>(i)));
    if (i % 10 == 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  const auto st = w->stats();
  ASSERT_EQ(st.state, SessionWriter::State::failed);
  EXPECT_NE(st.error.find("No space left on device"), std::string::npos) << st.error;
  EXPECT_NE(st.error.find(path), std::string::npos) << st.error;
  EXPECT_FALSE(w->append_pose(make_pose(999999)));  // refused at once after the failure
  EXPECT_FALSE(w->close());
  EXPECT_EQ(callbacks.load(), 1);
  EXPECT_EQ(message, st.error);
  EXPECT_GT(st.blocks_durable, 10u);
  SessionReader r;
  ASSERT_TRUE(r.open(path, &err)) << err;
  SessionReader::Block b;
  uint64_t n = 0;
  while (r.next(b)) {
    ASSERT_EQ(b.pose.frame, n);  // every frame in order from the first: nothing earlier lost
    ++n;
  }
  EXPECT_EQ(n, st.blocks_durable);
  EXPECT_EQ(r.end(), SessionReader::End::clean) << r.tail_reason();
  ::umount2(dir.path().c_str(), MNT_DETACH);
}

TEST(Session, ReadOnlyFileSystemRefusesTheRecordingWithAClearError) {
  if (const std::string why = test_mounts_unavailable(); !why.empty())
    GTEST_SKIP() << "needs root and a private mount namespace for a read-only tmpfs: " << why;
  TempDir dir;
  ASSERT_EQ(mount_small_tmpfs(dir.path(), MS_RDONLY), "");
  std::string err;
  EXPECT_FALSE(SessionWriter::create(dir.file("ro.mocap"), make_header(), {}, &err));
  EXPECT_NE(err.find("Read-only file system"), std::string::npos) << err;
  ::umount2(dir.path().c_str(), MNT_DETACH);
}

TEST(Session, DirectoryWithoutWritePermissionRefusesTheRecording) {
  // Root ignores permissions, so the attempt runs in a child that drops to "nobody".
  TempDir dir;
  ASSERT_EQ(::chmod(dir.path().c_str(), 0755), 0);
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::close(fds[0]);
    if (::geteuid() == 0 && (::setgid(65534) != 0 || ::setuid(65534) != 0)) ::_exit(3);
    std::string e;
    auto w = SessionWriter::create(dir.file("denied.mocap"), make_header(), {}, &e);
    const ssize_t wr = ::write(fds[1], e.data(), e.size());
    (void)wr;
    ::_exit(w ? 1 : 0);
  }
  ::close(fds[1]);
  char buf[512] = {};
  const ssize_t n = ::read(fds[0], buf, sizeof buf - 1);
  ::close(fds[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  ASSERT_NE(WEXITSTATUS(status), 3) << "could not drop privileges";
  EXPECT_EQ(WEXITSTATUS(status), 0) << "recording was created without write permission";
  EXPECT_GT(n, 0);
  EXPECT_NE(std::string(buf).find("Permission denied"), std::string::npos) << buf;
}
