// SessionReader: reads a session file (docs/session-format.md) block by block. Rejects unknown
// versions and foreign files with a clear message; stops at the first torn or corrupt block
// and reports where, keeping every good block before it. Lengths are checked against the
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
    uint64_t offset = 0;        ///< file offset of the block
    uint16_t device_index = 0;  ///< raw
    int64_t t_host_ns = 0;      ///< raw
    std::span<const uint8_t> raw;
    ImuSample sample;
    PoseFrame pose;
  };
  enum class End : uint8_t {
    not_reached,  ///< next() has not returned false yet
    clean,        ///< the file ends exactly after a whole block
    torn,         ///< the last block is incomplete (crash or power loss while writing)
    corrupt,      ///< a block fails its checksum or does not decode
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

  /// Continues reading at `offset`, the offset of a block returned earlier by next() (random
  /// access for playback). False, and nothing changes, if it lies outside the file's blocks.
  bool seek(uint64_t offset);

  End end() const { return end_; }
  /// Offset of the first byte not part of a good block (the file size after a clean end).
  uint64_t tail_offset() const { return offset_; }
  /// Bytes after tail_offset() that were ignored.
  uint64_t ignored_bytes() const { return size_ > offset_ ? size_ - offset_ : 0; }
  /// Why reading stopped early (empty after a clean end).
  const std::string& tail_reason() const { return tail_reason_; }
  /// Blocks of a type this version does not know, skipped (checksum-valid).
  uint64_t unknown_blocks() const { return unknown_blocks_; }

 private:
  bool read_header(const std::string& name, std::string* error);
  bool stop(End end, std::string reason);

  std::FILE* file_ = nullptr;
  std::vector<uint8_t> memory_;
  uint64_t size_ = 0;
  uint64_t offset_ = 0;
  uint64_t header_bytes_ = 0;  ///< offset of the first block
  session::SessionHeader header_;
  std::vector<uint8_t> payload_;
  End end_ = End::not_reached;
  std::string tail_reason_;
  uint64_t unknown_blocks_ = 0;
};

}  // namespace mocap
