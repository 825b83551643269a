// SessionReader: reads a session file (docs/session-format.md) block by block. Rejects unknown
// versions and foreign files with a clear message; recovers a damaged header from its copy
// (header_copy blocks); skips a damaged block by resynchronising on the next valid one (sync
// marker, length, CRC, decodes) and reports each damaged range (bytes and time span); a torn
// tail ends reading. Compressed blocks (zstd) are unpacked and their blocks delivered one by one;
// clock blocks update the wall-clock offset (unix_offset_ns()). Lengths are checked against the
// format's limits before anything is allocated.
#pragma once

#include <cstdint>
#include <cstdio>
#include <span>
#include <string>
#include <vector>

#include "mocap/session/format.hpp"

namespace mocap {

class SessionReader {
 public:
  /// One block as read. Only the member matching `type` is meaningful; `raw` points into the
  /// reader's buffer and stays valid until the next call to next().
  struct Block {
    session::BlockType type = session::BlockType::raw;
    uint64_t offset = 0;  ///< file offset of the block (or of the compressed block holding it)
    uint32_t inner = 0;   ///< inside a compressed block: 1 + its offset there; else 0
    uint16_t device_index = 0;  ///< raw
    int64_t t_host_ns = 0;      ///< raw
    std::span<const uint8_t> raw;
    int64_t t_unix_ns = 0;  ///< clock: CLOCK_REALTIME at t_host_ns (internal: next() absorbs it)
    ImuSample sample;
    PoseFrame pose;
  };
  enum class End : uint8_t {
    not_reached,  ///< next() has not returned false yet
    clean,        ///< the file ends exactly after a whole block
    torn,         ///< the last block is incomplete (crash or power loss while writing)
    corrupt,      ///< damaged data was skipped (see damaged()) or ends the file
  };
  /// Bytes skipped because they are not a valid block (damage), between two good blocks or
  /// before a corrupt (not merely torn) end.
  struct DamagedRange {
    uint64_t begin = 0, end = 0;  ///< file offsets [begin, end)
    int64_t t_before_ns = -1;     ///< host time of the last good block before (-1: none)
    int64_t t_after_ns = -1;      ///< host time of the first good block after (-1: none)
    std::string reason;           ///< what was wrong at `begin`
  };

  SessionReader() = default;
  ~SessionReader();
  SessionReader(const SessionReader&) = delete;
  SessionReader& operator=(const SessionReader&) = delete;

  /// Opens a file and reads its header. False with a message on failure.
  bool open(const std::string& path, std::string* error);
  /// Same, over a copy of bytes in memory (fuzzing, tests).
  bool open_bytes(std::span<const uint8_t> bytes, std::string* error);

  const session::SessionHeader& header() const { return header_; }
  /// Reads the next block; false at the end of the good data (see end(), tail_offset()).
  bool next(Block& block);

  /// Continues reading at a block returned earlier by next(): its `offset` and `inner` (random
  /// access for playback). False, and nothing changes, if it lies outside the file's blocks.
  bool seek(uint64_t offset, uint32_t inner = 0);

  /// CLOCK_REALTIME minus CLOCK_MONOTONIC (ns) as last recorded before the block just read:
  /// from the header, then from each clock block. unix time of a block = t_host_ns + this.
  int64_t unix_offset_ns() const { return unix_offset_ns_; }
  /// Compressed blocks unpacked so far.
  uint64_t compressed_blocks() const { return compressed_blocks_; }

  End end() const { return end_; }
  /// While reading: the offset of the next block; at the end: the first byte after the last
  /// good block (the file size after a clean end).
  uint64_t tail_offset() const { return offset_; }
  /// Bytes after tail_offset() that were ignored.
  uint64_t ignored_bytes() const { return size_ > offset_ ? size_ - offset_ : 0; }
  /// Why reading ended early, or the first damage skipped (empty after a clean, undamaged end).
  const std::string& tail_reason() const { return tail_reason_; }
  /// Every damaged range skipped so far, in file order.
  const std::vector<DamagedRange>& damaged() const { return damaged_; }
  /// Total bytes in damaged() ranges.
  uint64_t damaged_bytes() const;
  /// The header was damaged and read from its copy (header_copy blocks); why it was damaged.
  bool header_recovered() const { return !header_damage_.empty(); }
  const std::string& header_damage() const { return header_damage_; }
  /// Blocks of a type this version does not know, skipped (checksum-valid).
  uint64_t unknown_blocks() const { return unknown_blocks_; }

 private:
  /// Outcome of reading one block at an offset.
  enum class Parse : uint8_t { ok, skip, eof, bad };
  bool read_header(const std::string& name, std::string* error);
  bool recover_header(std::string* why);
  bool primary_crc_ok();
  void skip_header_copies();
  bool stop(End end, std::string reason);
  std::size_t read_at(uint64_t offset, uint8_t* dst, std::size_t n);
  /// Reads and checks the block at `at`; on bad: `end_kind` (torn or corrupt) and `why`.
  Parse parse_at(uint64_t at, Block& block, uint64_t& block_end, End& end_kind, std::string& why);
  /// Decodes a payload of a known type into block (block.type set); false if it does not.
  bool decode_payload(std::span<const uint8_t> payload, Block& block);
  /// Unpacks a compressed block's payload into group_; false (with why) if it does not.
  bool unpack(std::span<const uint8_t> payload, std::string& why);
  std::size_t unpacked_len_ = 0;  ///< bytes in group_ after the last unpack()
  /// Bookkeeping for a good block (time, open damage, clock); false if it is not delivered.
  bool deliver(const Block& block);
  /// Reads the block at group_pos_ in group_ (ok, skip: unknown type, bad: damaged).
  Parse next_inner(Block& block);
  /// The offset of the next valid block after `from` (UINT64_MAX if none).
  uint64_t resync(uint64_t from, Block& scratch, uint64_t limit);

  /// Reads up to n bytes at offset from fd_ (fewer only at the end of the file or on an error).
  std::size_t pread_full(uint64_t offset, uint8_t* dst, std::size_t n);
  /// The file's bytes [buffer_offset_, buffer_offset_ + buffer_len_): read_at reads in large
  /// blocks (a block is read as two small reads).
  std::vector<char> file_buffer_;
  uint64_t buffer_offset_ = 0, buffer_len_ = 0;
  int fd_ = -1;
  std::vector<uint8_t> memory_;
  uint64_t size_ = 0;
  uint64_t offset_ = 0;
  uint64_t header_bytes_ = 0;  ///< offset of the first block
  session::SessionHeader header_;
  std::vector<uint8_t> payload_;
  End end_ = End::not_reached;
  std::string tail_reason_;
  uint64_t unknown_blocks_ = 0;
  std::vector<DamagedRange> damaged_;
  bool damage_open_ = false;  ///< damaged_.back() waits for its t_after_ns
  int64_t last_t_ns_ = -1;    ///< host time of the last good block
  std::string header_damage_;
  std::vector<uint8_t> scan_;   ///< resync window
  std::vector<uint8_t> group_;  ///< an unpacked compressed block
  std::size_t group_len_ = 0, group_pos_ = 0;
  uint64_t group_offset_ = 0, group_end_ = 0;  ///< the compressed block's file range
  uint64_t compressed_blocks_ = 0;
  int64_t unix_offset_ns_ = 0;
  void* dctx_ = nullptr;  ///< ZSTD_DCtx
};

}  // namespace mocap
