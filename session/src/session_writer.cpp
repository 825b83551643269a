// SessionWriter: preallocated ring hand-off from the pipeline to a writer thread that appends
// the ring to the session file and fdatasync()s it every flush interval; write errors stop the
// recording cleanly (the torn last block is cut off so the file ends on a whole block). With
// compression on, this thread packs runs of blocks into zstd `compressed` blocks; it also
// writes the `clock` blocks (wall clock beside the monotonic one).
#include "mocap/session/session_writer.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include "block_crc.hpp"

namespace mocap {
namespace {

/// Writes all of [data, data+len); returns 0 or the errno of the failure, and how much went out.
int write_all(int fd, const uint8_t* data, std::size_t len, std::size_t& written) {
  written = 0;
  while (written < len) {
    const ssize_t n = ::write(fd, data + written, len - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      return errno;
    }
    if (n == 0) return EIO;
    written += static_cast<std::size_t>(n);
  }
  return 0;
}

/// fdatasync, except that files that cannot be synced (pipes, character devices: EINVAL) are
/// accepted as they are, so a session can also be recorded into a pipe.
int sync_fd(int fd) {
  if (::fdatasync(fd) == 0 || errno == EINVAL) return 0;
  return errno;
}

std::string describe(int err) {
  std::string m = std::strerror(err);
  if (err == ENOSPC || err == EDQUOT) m += " (disk full)";
  return m;
}

/// Uncompressed bytes packed into one compressed block at most (the packed result must also fit
/// a block's payload limit, else the run is written as it is).
constexpr std::size_t kGroupTarget = 128u * 1024;
static_assert(kGroupTarget <= session::kMaxGroupBytes);
static_assert(session::kBlockHeaderBytes + session::kMaxBlockPayload +
                  session::kBlockTrailerBytes <=
              kGroupTarget);

int64_t clock_ns(clockid_t id) {
  timespec ts{};
  ::clock_gettime(id, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

}  // namespace

struct SessionWriter::ZstdContext {
  ZSTD_CCtx* cctx = ZSTD_createCCtx();
  ~ZstdContext() { ZSTD_freeCCtx(cctx); }
};

SessionWriter::SessionWriter(std::string path, int fd, Options options, uint64_t header_bytes)
    : path_(std::move(path)), fd_(fd), options_(std::move(options)) {
  capacity_ = std::max<std::size_t>(options_.buffer_bytes, 4 * session::kMaxBlockPayload);
  ring_ = std::make_unique<uint8_t[]>(capacity_);
  std::memset(ring_.get(), 0, capacity_);  // touch the pages now, not on the pipeline's time
  bytes_durable_ = header_bytes;
  if (options_.flush_interval_ms <= 0 || options_.flush_interval_ms > 100)
    options_.flush_interval_ms = 50;
  if (options_.compression == Options::Compression::zstd) {
    stage_ = std::make_unique<uint8_t[]>(kGroupTarget);
    packed_capacity_ = session::kBlockHeaderBytes + session::kCompressedPrefixBytes +
                       ZSTD_compressBound(kGroupTarget) + session::kBlockTrailerBytes;
    packed_ = std::make_unique<uint8_t[]>(packed_capacity_);
    zstd_ = std::make_unique<ZstdContext>();
    options_.compression_level = std::clamp(options_.compression_level, 1, ZSTD_maxCLevel());
  }
}

SessionWriter::~SessionWriter() {
  close();
}

std::unique_ptr<SessionWriter> SessionWriter::create(const std::string& path,
                                                     const session::SessionHeader& header,
                                                     Options options, std::string* error) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    if (error) *error = "cannot create session file '" + path + "': " + describe(errno);
    return nullptr;
  }
  return create_fd(fd, path, header, std::move(options), error);
}

std::unique_ptr<SessionWriter> SessionWriter::create_fd(int fd, const std::string& path,
                                                        const session::SessionHeader& header,
                                                        Options options, std::string* error) {
  std::vector<uint8_t> bytes;
  if (!session::encode_file_header(header, bytes, error)) {
    ::close(fd);
    return nullptr;
  }
  // The header again in header_copy blocks: one damaged header byte loses nothing.
  const std::vector<uint8_t> prefix = bytes;
  session::encode_header_copy_blocks(prefix, bytes);
  std::size_t written = 0;
  int err = write_all(fd, bytes.data(), bytes.size(), written);
  if (!err) err = sync_fd(fd);
  if (err) {
    if (error) *error = "cannot write session file '" + path + "': " + describe(err);
    ::close(fd);
    return nullptr;
  }
  // Make the new directory entry durable too (best effort: some file systems refuse).
  const auto slash = path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "." : path.substr(0, slash + 1);
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
  std::unique_ptr<SessionWriter> w(new SessionWriter(path, fd, std::move(options), bytes.size()));
  w->clock_host_ns_ = header.t_start_host_ns;
  w->clock_offset_ns_ = header.t_start_unix_ns - header.t_start_host_ns;
  w->thread_ = std::thread([p = w.get()] { p->run(); });
  return w;
}

bool SessionWriter::append_raw(uint16_t device_index, int64_t t_host_ns,
                               std::span<const uint8_t> bytes) noexcept {
  uint8_t prefix[session::kRawPrefixBytes];
  session::encode_raw_prefix(device_index, t_host_ns, prefix);
  bool ok = true;
  do {
    const std::size_t n = std::min(bytes.size(), session::kMaxRawChunk);
    ok = append_block(session::BlockType::raw, prefix, sizeof prefix, bytes.data(), n) && ok;
    bytes = bytes.subspan(n);
  } while (!bytes.empty());
  return ok;
}

bool SessionWriter::append_sample(const ImuSample& sample) noexcept {
  uint8_t payload[session::kSamplePayloadBytes];
  session::encode_sample(sample, payload);
  return append_block(session::BlockType::sample, nullptr, 0, payload, sizeof payload);
}

bool SessionWriter::append_pose(const PoseFrame& frame) noexcept {
  uint8_t payload[session::kMaxPosePayload];
  const std::size_t n = session::encode_pose(frame, payload);
  return append_block(session::BlockType::pose, nullptr, 0, payload, n);
}

bool SessionWriter::append_block(session::BlockType type, const uint8_t* prefix,
                                 std::size_t prefix_len, const uint8_t* body,
                                 std::size_t body_len) noexcept {
  const std::size_t payload_len = prefix_len + body_len;
  uint8_t head[session::kBlockHeaderBytes];
  session::encode_block_header(type, static_cast<uint32_t>(payload_len), head);
  uint32_t crc = session::block_crc(0, head, sizeof head);
  if (prefix_len) crc = session::block_crc(crc, prefix, static_cast<std::size_t>(prefix_len));
  if (body_len) crc = session::block_crc(crc, body, static_cast<std::size_t>(body_len));
  uint8_t tail[session::kBlockTrailerBytes];
  session::put_u32(tail, static_cast<uint32_t>(crc));
  std::lock_guard lock(mutex_);
  return push_locked(head, prefix, prefix_len, body, body_len, tail, true);
}

bool SessionWriter::push_locked(const uint8_t* head, const uint8_t* prefix, std::size_t prefix_len,
                                const uint8_t* body, std::size_t body_len, const uint8_t* tail,
                                bool counted) noexcept {
  const std::size_t total =
      session::kBlockHeaderBytes + prefix_len + body_len + session::kBlockTrailerBytes;
  if (state_.load(std::memory_order_relaxed) != State::recording || stop_ ||
      capacity_ - (head_ - tail_) < total) {
    if (counted) ++blocks_dropped_;
    return false;
  }
  auto copy_in = [&](const uint8_t* src, std::size_t len) {
    const std::size_t pos = head_ % capacity_;
    const std::size_t first = std::min(len, capacity_ - pos);
    std::memcpy(ring_.get() + pos, src, first);
    if (len > first) std::memcpy(ring_.get(), src + first, len - first);
    head_ += len;
  };
  copy_in(head, session::kBlockHeaderBytes);
  if (prefix_len) copy_in(prefix, prefix_len);
  if (body_len) copy_in(body, body_len);
  copy_in(tail, session::kBlockTrailerBytes);
  if (counted) ++blocks_appended_;
  const std::size_t used = static_cast<std::size_t>(head_ - tail_);
  high_water_ = std::max(high_water_, used);
  if (used > capacity_ / 2) cv_.notify_one();
  return true;
}

void SessionWriter::maybe_append_clock(int64_t now_host_ns) {
  const int64_t unix_ns = clock_ns(CLOCK_REALTIME);
  const int64_t offset = unix_ns - now_host_ns;
  const bool moved = std::llabs(offset - clock_offset_ns_) > 1'000'000;
  const bool due = options_.clock_interval_ms > 0 &&
                   now_host_ns - clock_host_ns_ >= options_.clock_interval_ms * 1'000'000ll;
  if (!moved && !due) return;
  uint8_t payload[session::kClockPayloadBytes];
  session::put_u64(payload, static_cast<uint64_t>(now_host_ns));
  session::put_u64(payload + 8, static_cast<uint64_t>(unix_ns));
  uint8_t head[session::kBlockHeaderBytes];
  session::encode_block_header(session::BlockType::clock, sizeof payload, head);
  uint32_t crc = session::block_crc(0, head, sizeof head);
  crc = session::block_crc(crc, payload, sizeof payload);
  uint8_t tail[session::kBlockTrailerBytes];
  session::put_u32(tail, static_cast<uint32_t>(crc));
  if (push_locked(head, nullptr, 0, payload, sizeof payload, tail, false)) {
    clock_host_ns_ = now_host_ns;
    clock_offset_ns_ = offset;
  }
}

SessionWriter::Round SessionWriter::write_plain(std::size_t pos, std::size_t len) {
  Round r;
  const std::size_t first = std::min(len, capacity_ - pos);
  std::size_t w1 = 0, w2 = 0;
  r.err = write_all(fd_, ring_.get() + pos, first, w1);
  if (!r.err && len > first) r.err = write_all(fd_, ring_.get(), len - first, w2);
  if (!r.err && (r.err = sync_fd(fd_)) != 0) r.what = "cannot sync session file";
  // Count the whole blocks in what reached the file (all of it, unless an error cut it short).
  const std::size_t reached = w1 + w2;
  std::size_t whole = 0;
  while (whole + session::kBlockHeaderBytes <= reached) {
    uint8_t hdr[session::kBlockHeaderBytes];
    for (std::size_t i = 0; i < sizeof hdr; ++i)
      hdr[i] = ring_[(pos + whole + i) % capacity_];
    const std::size_t block =
        session::kBlockHeaderBytes + session::get_u32(hdr + 4) + session::kBlockTrailerBytes;
    if (whole + block > reached) break;
    whole += block;
    r.blocks += hdr[2] != static_cast<uint8_t>(session::BlockType::clock);
  }
  r.file_bytes = r.in_bytes = whole;
  // On an error, keep the whole blocks that did reach the file and cut the torn one off.
  if (r.err)
    r.cut_ok =
        ::ftruncate(fd_, static_cast<off_t>(bytes_durable_ + whole)) == 0 && sync_fd(fd_) == 0;
  return r;
}

SessionWriter::Round SessionWriter::write_compressed(std::size_t pos, std::size_t len) {
  Round r;
  std::size_t done = 0;
  while (done < len && !r.err) {
    // A run of whole blocks, up to kGroupTarget bytes (a single bigger block cannot occur).
    std::size_t run = 0;
    uint64_t blocks = 0;
    while (done + run < len) {
      uint8_t hdr[session::kBlockHeaderBytes];
      for (std::size_t i = 0; i < sizeof hdr; ++i)
        hdr[i] = ring_[(pos + done + run + i) % capacity_];
      const std::size_t block =
          session::kBlockHeaderBytes + session::get_u32(hdr + 4) + session::kBlockTrailerBytes;
      if (run + block > kGroupTarget) break;
      const std::size_t from = (pos + done + run) % capacity_;
      const std::size_t first = std::min(block, capacity_ - from);
      std::memcpy(stage_.get() + run, ring_.get() + from, first);
      if (block > first) std::memcpy(stage_.get() + run + first, ring_.get(), block - first);
      run += block;
      blocks += hdr[2] != static_cast<uint8_t>(session::BlockType::clock);
    }
    // Pack it when that is smaller and fits a block; else write it as it is.
    constexpr std::size_t kOverhead =
        session::kBlockHeaderBytes + session::kCompressedPrefixBytes + session::kBlockTrailerBytes;
    uint8_t* body = packed_.get() + session::kBlockHeaderBytes + session::kCompressedPrefixBytes;
    const std::size_t c = ZSTD_compressCCtx(zstd_->cctx, body, packed_capacity_ - kOverhead,
                                            stage_.get(), run, options_.compression_level);
    const uint8_t* out = stage_.get();
    std::size_t out_len = run;
    if (!ZSTD_isError(c) && session::kCompressedPrefixBytes + c <= session::kMaxBlockPayload &&
        c + kOverhead < run) {
      const auto payload_len = static_cast<uint32_t>(session::kCompressedPrefixBytes + c);
      session::encode_block_header(session::BlockType::compressed, payload_len, packed_.get());
      session::put_u32(packed_.get() + session::kBlockHeaderBytes, static_cast<uint32_t>(run));
      const uint32_t crc =
          session::block_crc(0, packed_.get(), session::kBlockHeaderBytes + payload_len);
      session::put_u32(packed_.get() + session::kBlockHeaderBytes + payload_len,
                       static_cast<uint32_t>(crc));
      out = packed_.get();
      out_len = c + kOverhead;
    }
    std::size_t written = 0;
    r.err = write_all(fd_, out, out_len, written);
    if (r.err) break;
    r.file_bytes += out_len;
    r.blocks += blocks;
    r.in_bytes += run;
    done += run;
  }
  if (!r.err && (r.err = sync_fd(fd_)) != 0) r.what = "cannot sync session file";
  // On an error, keep the runs written whole before it and cut the torn one off.
  if (r.err)
    r.cut_ok = ::ftruncate(fd_, static_cast<off_t>(bytes_durable_ + r.file_bytes)) == 0 &&
               sync_fd(fd_) == 0;
  return r;
}

void SessionWriter::run() {
  std::unique_lock lock(mutex_);
  for (;;) {
    cv_.wait_for(lock, std::chrono::milliseconds(options_.flush_interval_ms),
                 [&] { return stop_ || head_ - tail_ > capacity_ / 2; });
    if (!stop_) maybe_append_clock(clock_ns(CLOCK_MONOTONIC));
    const uint64_t head = head_, tail = tail_, blocks = blocks_appended_;
    const bool stopping = stop_;
    if (head != tail) {
      lock.unlock();
      // The ring region [tail, head) belongs to this thread until tail_ moves.
      const std::size_t len = static_cast<std::size_t>(head - tail);
      const std::size_t pos = tail % capacity_;
      const Round r = zstd_ ? write_compressed(pos, len) : write_plain(pos, len);
      const int64_t cpu = clock_ns(CLOCK_THREAD_CPUTIME_ID);
      lock.lock();
      writer_cpu_ns_ = cpu;
      if (r.err) {
        if (r.cut_ok) {
          bytes_durable_ += r.file_bytes;
          blocks_durable_ += r.blocks;
          bytes_uncompressed_ += r.in_bytes;
          bytes_blocks_ += r.file_bytes;
        }
        blocks_dropped_ += blocks_appended_ - blocks_durable_;
        tail_ = head;
        fail(r.err, r.what);
        break;
      }
      tail_ = head;
      blocks_durable_ = blocks;
      bytes_durable_ += r.file_bytes;
      bytes_uncompressed_ += r.in_bytes;
      bytes_blocks_ += r.file_bytes;
      ++flushes_;
    }
    if (stopping) break;
  }
  if (state_.load() == State::failed && options_.on_error) {
    const std::string message = error_;
    lock.unlock();
    options_.on_error(message);
  }
}

void SessionWriter::fail(int err, const char* what) {
  error_ = std::string("recording stopped: ") + what + " '" + path_ + "': " + describe(err) +
           "; the " + std::to_string(blocks_durable_) + " blocks (" +
           std::to_string(bytes_durable_) + " bytes) before it are intact";
  state_.store(State::failed);
}

bool SessionWriter::close() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  cv_.notify_one();
  if (thread_.joinable()) thread_.join();
  if (fd_ >= 0) {
    ::close(fd_);
    fd_ = -1;
  }
  State expected = State::recording;
  state_.compare_exchange_strong(expected, State::closed);
  return state_.load() != State::failed;
}

SessionWriter::Stats SessionWriter::stats() const {
  std::lock_guard lock(mutex_);
  Stats s;
  s.state = state_.load();
  s.blocks_appended = blocks_appended_;
  s.blocks_dropped = blocks_dropped_;
  s.blocks_durable = blocks_durable_;
  s.bytes_durable = bytes_durable_;
  s.flushes = flushes_;
  s.buffer_high_water = high_water_;
  s.bytes_uncompressed = bytes_uncompressed_;
  s.bytes_blocks = bytes_blocks_;
  s.writer_cpu_ns = writer_cpu_ns_;
  s.error = error_;
  return s;
}

}  // namespace mocap
