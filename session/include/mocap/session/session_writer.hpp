// SessionWriter: records a session file (docs/session-format.md) without ever blocking the
// pipeline. append_*() encode a checksummed block into a preallocated ring under a short lock;
// a writer thread write()s and fdatasync()s the ring every flush interval. A full buffer drops
// (and counts) blocks; a write error (disk full, read-only, I/O error) stops the recording with
// a clear message and leaves everything flushed before it readable. With compression on, the
// writer thread (never a producer) compresses runs of blocks into zstd `compressed` blocks; it
// also records the wall clock beside the monotonic one in `clock` blocks.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <thread>

#include "mocap/session/format.hpp"

namespace mocap {

class SessionWriter {
 public:
  struct Options {
    std::size_t buffer_bytes = 8u << 20;  ///< hand-off ring; about 10 s of a 16-sensor rig
    int flush_interval_ms = 50;           ///< write + fdatasync at least this often
    /// none: blocks as appended; zstd: runs of up to 128 KiB of blocks compressed together
    /// into one `compressed` block (on the writer thread) when that is smaller.
    enum class Compression : uint8_t { none, zstd } compression = Compression::none;
    int compression_level = 3;  ///< zstd level, 1 (fast) .. 19
    /// A clock block (wall clock beside the monotonic one) at least this often, and whenever
    /// the two clocks' offset moved by more than 1 ms (NTP step); 0: only at those moves.
    int clock_interval_ms = 10000;
    /// Called once, from the writer thread, when a write error stops the recording.
    std::function<void(const std::string& message)> on_error;
  };
  enum class State : uint8_t { recording, closed, failed };
  struct Stats {
    State state = State::closed;
    uint64_t blocks_appended = 0;  ///< accepted into the buffer (these counts leave out the
                                   ///< writer's own clock blocks)
    uint64_t blocks_dropped = 0;   ///< refused: buffer full (writer behind) or recording stopped
    uint64_t blocks_durable = 0;   ///< written and fdatasync'ed
    uint64_t bytes_durable = 0;    ///< file size known to be on disk, header included
    uint64_t flushes = 0;          ///< write + fdatasync rounds
    std::size_t buffer_high_water = 0;  ///< most bytes ever waiting in the buffer
    uint64_t bytes_uncompressed = 0;    ///< blocks written, as they were before compression
    uint64_t bytes_blocks = 0;          ///< the same blocks as written to the file
    int64_t writer_cpu_ns = 0;          ///< CPU time of the writer thread so far
    std::string error;                  ///< why the recording stopped (state == failed)
  };

  ~SessionWriter();
  SessionWriter(const SessionWriter&) = delete;
  SessionWriter& operator=(const SessionWriter&) = delete;

  /// Creates (truncates) the file, writes and syncs the header, starts the writer thread.
  /// Returns nullptr with a message naming the path and the system error on failure.
  static std::unique_ptr<SessionWriter> create(const std::string& path,
                                               const session::SessionHeader& header,
                                               Options options, std::string* error);
  /// Same on a file the caller opened for writing (e.g. created exclusively); takes the fd
  /// (closed on failure too). `path` names the file in messages.
  static std::unique_ptr<SessionWriter> create_fd(int fd, const std::string& path,
                                                  const session::SessionHeader& header,
                                                  Options options, std::string* error);

  // Producers (the pipeline thread; safe from several threads). Never block on I/O, never
  // allocate. Return false if the block was dropped (buffer full or recording stopped).
  /// Raw device bytes; chunks longer than 64 KiB become several blocks.
  bool append_raw(uint16_t device_index, int64_t t_host_ns,
                  std::span<const uint8_t> bytes) noexcept;
  bool append_sample(const ImuSample& sample) noexcept;
  bool append_pose(const PoseFrame& frame) noexcept;

  /// Writes and syncs everything buffered, stops the thread, closes the file. Returns false if
  /// the recording had failed (see stats().error). Idempotent; the destructor calls it.
  bool close();
  Stats stats() const;
  const std::string& path() const { return path_; }

 private:
  SessionWriter(std::string path, int fd, Options options, uint64_t header_bytes);
  bool append_block(session::BlockType type, const uint8_t* prefix, std::size_t prefix_len,
                    const uint8_t* body, std::size_t body_len) noexcept;
  /// Result of writing one round [tail, head) of the ring.
  struct Round {
    int err = 0;
    const char* what = "cannot write session file";
    uint64_t file_bytes = 0;  ///< bytes written (whole blocks, after a failure: those kept)
    uint64_t blocks = 0;      ///< appended blocks they hold
    uint64_t in_bytes = 0;    ///< their size before compression
    bool cut_ok = true;       ///< after a failure: the file was cut back to file_bytes
  };
  bool push_locked(const uint8_t* head, const uint8_t* prefix, std::size_t prefix_len,
                   const uint8_t* body, std::size_t body_len, const uint8_t* tail,
                   bool counted) noexcept;
  Round write_plain(std::size_t pos, std::size_t len);
  Round write_compressed(std::size_t pos, std::size_t len);
  void maybe_append_clock(int64_t now_host_ns);
  void run();
  void fail(int err, const char* what);

  std::string path_;
  int fd_ = -1;
  Options options_;
  std::unique_ptr<uint8_t[]> ring_;
  std::size_t capacity_ = 0;
  // Writer-thread only: compression staging, the zstd context, the last clock block.
  std::unique_ptr<uint8_t[]> stage_;
  std::unique_ptr<uint8_t[]> packed_;
  std::size_t packed_capacity_ = 0;
  struct ZstdContext;
  std::unique_ptr<ZstdContext> zstd_;
  int64_t clock_host_ns_ = 0;
  int64_t clock_offset_ns_ = 0;

  mutable std::mutex mutex_;  // guards the fields below (held only for index updates/copies)
  std::condition_variable cv_;
  uint64_t head_ = 0;  // bytes ever appended (ring position = head_ % capacity_)
  uint64_t tail_ = 0;  // bytes ever written to the file
  uint64_t blocks_appended_ = 0;
  uint64_t blocks_dropped_ = 0;
  uint64_t blocks_durable_ = 0;
  uint64_t bytes_durable_ = 0;
  uint64_t flushes_ = 0;
  std::size_t high_water_ = 0;
  uint64_t bytes_uncompressed_ = 0;
  uint64_t bytes_blocks_ = 0;
  int64_t writer_cpu_ns_ = 0;
  bool stop_ = false;
  std::string error_;

  std::atomic<State> state_{State::recording};
  std::thread thread_;
};

}  // namespace mocap
