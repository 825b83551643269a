// SessionReader: header validation (magic, byte order, version, limits, CRC) with recovery
// from the header_copy blocks, and block iteration that skips damage by resynchronising on the
// next valid block (sync marker, length, CRC, decodes), recording each damaged range; a torn
// tail ends reading.
#include "mocap/session/session_reader.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <functional>
#include <limits>
#include "block_crc.hpp"

namespace mocap {

using namespace session;

namespace {

constexpr uint64_t kNone = std::numeric_limits<uint64_t>::max();
constexpr std::size_t kFixedHeaderBytes = 20;

/// Checks and decodes a file header read through `read(offset, dst, n)` from a stream of `size`
/// bytes; `header_bytes` is its length (magic to CRC). False with a message.
bool parse_file_header(const std::function<std::size_t(uint64_t, uint8_t*, std::size_t)>& read,
                       uint64_t size, SessionHeader& header, uint64_t& header_bytes,
                       std::string& msg) {
  uint8_t fixed[kFixedHeaderBytes];
  const std::size_t got = read(0, fixed, sizeof fixed);
  if (got < sizeof kMagic || std::memcmp(fixed, kMagic, sizeof kMagic) != 0) {
    msg = "not a mocap session file (no MOCAPSES signature)";
    return false;
  }
  if (got < sizeof fixed) {
    msg = "session header truncated";
    return false;
  }
  const uint32_t version = get_u32(fixed + 8);
  const uint32_t endian = get_u32(fixed + 12);
  if (endian != kEndianTag) {
    char b[16];
    std::snprintf(b, sizeof b, "%08x", endian);
    msg = "unknown byte-order tag 0x" + std::string(b) + " (expected little-endian 0x01020304)";
    return false;
  }
  if (version != kVersion) {
    msg = "session format version " + std::to_string(version) +
          " is not supported (this build reads version " + std::to_string(kVersion) + ")";
    return false;
  }
  const uint32_t len = get_u32(fixed + 16);
  if (len > kMaxHeaderBytes) {
    msg = "header length " + std::to_string(len) + " exceeds the 4 MiB limit";
    return false;
  }
  if (len + 24ull > size) {
    msg = "session header truncated";
    return false;
  }
  std::vector<uint8_t> buf(sizeof fixed + len + 4);
  std::memcpy(buf.data(), fixed, sizeof fixed);
  if (read(sizeof fixed, buf.data() + sizeof fixed, len + 4) != len + 4) {
    msg = "session header truncated";
    return false;
  }
  const auto crc = session::block_crc(0, buf.data(), static_cast<std::size_t>(buf.size() - 4));
  if (static_cast<uint32_t>(crc) != get_u32(buf.data() + buf.size() - 4)) {
    msg = "session header checksum mismatch (file damaged)";
    return false;
  }
  if (!decode_header_payload({buf.data() + sizeof fixed, len}, header, &msg)) return false;
  header_bytes = buf.size();
  return true;
}

int64_t block_time(const SessionReader::Block& b) {
  switch (b.type) {
    case BlockType::raw:
      return b.t_host_ns;
    case BlockType::sample:
      return b.sample.t_host_ns;
    case BlockType::pose:
      return b.pose.t_ns;
    case BlockType::clock:
      return b.t_host_ns;
    default:
      return -1;
  }
}

}  // namespace

SessionReader::~SessionReader() {
  if (fd_ >= 0) ::close(fd_);
  if (dctx_) ZSTD_freeDCtx(static_cast<ZSTD_DCtx*>(dctx_));
}

bool SessionReader::open(const std::string& path, std::string* error) {
  if (fd_ >= 0) ::close(fd_);
  memory_.clear();
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  buffer_offset_ = buffer_len_ = 0;
  if (fd_ < 0) {
    if (error) *error = "cannot open session file '" + path + "': " + std::strerror(errno);
    return false;
  }
  // Reading ahead in 1 MiB blocks: a long replay reads hundreds of megabytes, a block of ~140
  // bytes at a time (as two reads: header, then payload and checksum).
  file_buffer_.resize(1 << 20);
  struct stat st {};
  size_ = ::fstat(fd_, &st) == 0 ? static_cast<uint64_t>(st.st_size) : 0;
  return read_header("'" + path + "'", error);
}

bool SessionReader::open_bytes(std::span<const uint8_t> bytes, std::string* error) {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  memory_.assign(bytes.begin(), bytes.end());
  size_ = memory_.size();
  return read_header("session data", error);
}

std::size_t SessionReader::pread_full(uint64_t offset, uint8_t* dst, std::size_t n) {
  std::size_t got = 0;
  while (got < n) {
    const ssize_t r = ::pread(fd_, dst + got, n - got, static_cast<off_t>(offset + got));
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) break;
    got += static_cast<std::size_t>(r);
  }
  return got;
}

std::size_t SessionReader::read_at(uint64_t offset, uint8_t* dst, std::size_t n) {
  if (fd_ >= 0) {
    // Served from file_buffer_ (refilled at `offset` when it does not hold the range): no
    // stdio call, no lock, per block. Larger reads go to dst directly.
    if (offset < buffer_offset_ || offset + n > buffer_offset_ + buffer_len_) {
      if (n >= file_buffer_.size()) return pread_full(offset, dst, n);
      buffer_offset_ = offset;
      buffer_len_ =
          pread_full(offset, reinterpret_cast<uint8_t*>(file_buffer_.data()), file_buffer_.size());
    }
    if (offset >= buffer_offset_ + buffer_len_) return 0;
    const std::size_t got =
        std::min<std::size_t>(n, static_cast<std::size_t>(buffer_offset_ + buffer_len_ - offset));
    std::memcpy(dst, file_buffer_.data() + (offset - buffer_offset_), got);
    return got;
  }
  if (offset >= memory_.size()) return 0;
  const std::size_t got = std::min<std::size_t>(n, memory_.size() - offset);
  std::memcpy(dst, memory_.data() + offset, got);
  return got;
}

bool SessionReader::read_header(const std::string& name, std::string* error) {
  offset_ = 0;
  end_ = End::not_reached;
  tail_reason_.clear();
  unknown_blocks_ = 0;
  damaged_.clear();
  damage_open_ = false;
  last_t_ns_ = -1;
  header_damage_.clear();
  group_len_ = group_pos_ = 0;
  compressed_blocks_ = 0;
  payload_.resize(kMaxBlockPayload + kBlockTrailerBytes);
  std::string msg;
  const auto read = [this](uint64_t o, uint8_t* d, std::size_t n) { return read_at(o, d, n); };
  if (parse_file_header(read, size_, header_, header_bytes_, msg)) {
    offset_ = header_bytes_;
    unix_offset_ns_ = header_.t_start_unix_ns - header_.t_start_host_ns;
    skip_header_copies();
    return true;
  }
  // An intact header (valid CRC) of another version is that version, not damage.
  if (msg.find("is not supported") != std::string::npos && primary_crc_ok()) {
    if (error) *error = name + ": " + msg;
    return false;
  }
  if (recover_header(&header_damage_)) {
    header_damage_ = msg;
    unix_offset_ns_ = header_.t_start_unix_ns - header_.t_start_host_ns;
    return true;
  }
  if (error) *error = name + ": " + msg;
  return false;
}

bool SessionReader::primary_crc_ok() {
  uint8_t fixed[kFixedHeaderBytes];
  if (read_at(0, fixed, sizeof fixed) != sizeof fixed) return false;
  const uint32_t len = get_u32(fixed + 16);
  if (len > kMaxHeaderBytes || len + 24ull > size_) return false;
  std::vector<uint8_t> buf(sizeof fixed + len + 4);
  if (read_at(0, buf.data(), buf.size()) != buf.size()) return false;
  const auto crc = session::block_crc(0, buf.data(), static_cast<std::size_t>(buf.size() - 4));
  return static_cast<uint32_t>(crc) == get_u32(buf.data() + buf.size() - 4);
}

void SessionReader::skip_header_copies() {
  Block b;
  for (;;) {
    uint64_t block_end = 0;
    End kind = End::corrupt;
    std::string why;
    if (parse_at(offset_, b, block_end, kind, why) != Parse::ok || b.type != BlockType::header_copy)
      return;
    offset_ = block_end;
  }
}

bool SessionReader::recover_header(std::string* /*why*/) {
  // The copy follows the header: its first block starts within the largest header's reach.
  Block b;
  const uint64_t limit = kFixedHeaderBytes + kMaxHeaderBytes + 4 + 1;
  uint64_t at = resync(0, b, limit);
  std::vector<uint8_t> copy;
  uint32_t total = 0;
  while (at != kNone) {
    uint64_t block_end = 0;
    End kind = End::corrupt;
    std::string w;
    if (parse_at(at, b, block_end, kind, w) != Parse::ok || b.type != BlockType::header_copy ||
        b.raw.size() < kHeaderCopyPrefixBytes)
      break;
    const uint32_t t = get_u32(b.raw.data());
    const uint32_t off = get_u32(b.raw.data() + 4);
    if (t > kFixedHeaderBytes + kMaxHeaderBytes + 4 || (total && t != total) || off != copy.size())
      break;
    total = t;
    copy.insert(copy.end(), b.raw.begin() + kHeaderCopyPrefixBytes, b.raw.end());
    at = block_end;
    if (copy.size() >= total) break;
  }
  if (total == 0 || copy.size() != total) return false;
  const auto read = [&copy](uint64_t o, uint8_t* d, std::size_t n) -> std::size_t {
    if (o >= copy.size()) return 0;
    const std::size_t got = std::min<std::size_t>(n, copy.size() - o);
    std::memcpy(d, copy.data() + o, got);
    return got;
  };
  SessionHeader h;
  uint64_t hb = 0;
  std::string msg;
  if (!parse_file_header(read, copy.size(), h, hb, msg) || hb != copy.size()) return false;
  header_ = std::move(h);
  offset_ = header_bytes_ = at;  // the first block after the copy
  skip_header_copies();
  return true;
}

bool SessionReader::stop(End end, std::string reason) {
  end_ = end;
  tail_reason_ = std::move(reason);
  return false;
}

uint64_t SessionReader::damaged_bytes() const {
  uint64_t n = 0;
  for (const auto& d : damaged_)
    n += d.end - d.begin;
  return n;
}

bool SessionReader::seek(uint64_t offset, uint32_t inner) {
  if (offset < header_bytes_ || offset > size_) return false;
  if (inner) {
    Block b;
    uint64_t block_end = 0;
    End kind = End::corrupt;
    std::string why;
    if (parse_at(offset, b, block_end, kind, why) != Parse::ok || b.type != BlockType::compressed ||
        inner - 1 >= unpacked_len_)
      return false;
    group_len_ = unpacked_len_;
    group_pos_ = inner - 1;
    group_offset_ = offset;
    group_end_ = block_end;
    offset = block_end;
  } else {
    group_len_ = group_pos_ = 0;
  }
  offset_ = offset;
  end_ = End::not_reached;
  tail_reason_.clear();
  damage_open_ = false;
  last_t_ns_ = -1;
  return true;
}

SessionReader::Parse SessionReader::parse_at(uint64_t at, Block& block, uint64_t& block_end,
                                             End& end_kind, std::string& why) {
  uint8_t hdr[kBlockHeaderBytes];
  const std::size_t got = read_at(at, hdr, sizeof hdr);
  if (got == 0 && at >= size_) return Parse::eof;
  end_kind = End::corrupt;
  if (got < sizeof hdr) {
    end_kind = End::torn;
    why = "incomplete block header";
    return Parse::bad;
  }
  if (get_u16(hdr) != kBlockSync) {
    const bool zeros = std::all_of(hdr, hdr + sizeof hdr, [](uint8_t b) { return b == 0; });
    end_kind = zeros ? End::torn : End::corrupt;
    why = zeros ? "zero-filled tail" : "no block marker";
    return Parse::bad;
  }
  const uint32_t len = get_u32(hdr + 4);
  if (len > kMaxBlockPayload) {
    why = "block length " + std::to_string(len) + " exceeds the limit";
    return Parse::bad;
  }
  const std::size_t want = len + kBlockTrailerBytes;
  const std::size_t have = read_at(at + sizeof hdr, payload_.data(), want);
  if (have < want) {
    end_kind = End::torn;
    why =
        "last block truncated (" + std::to_string(have) + " of " + std::to_string(want) + " bytes)";
    return Parse::bad;
  }
  uint32_t crc = session::block_crc(0, hdr, sizeof hdr);
  crc = session::block_crc(crc, payload_.data(), len);
  block_end = at + sizeof hdr + want;
  if (static_cast<uint32_t>(crc) != get_u32(payload_.data() + len)) {
    end_kind = block_end == size_ ? End::torn : End::corrupt;
    why = std::string(block_end == size_ ? "last block" : "block") + " fails its checksum";
    return Parse::bad;
  }
  const std::span<const uint8_t> payload(payload_.data(), len);
  block.offset = at;
  block.inner = 0;
  block.type = static_cast<BlockType>(hdr[2]);
  if (block.type == BlockType::compressed) {
    if (!unpack(payload, why)) return Parse::bad;
    return Parse::ok;
  }
  if (static_cast<uint8_t>(block.type) == 0 || static_cast<uint8_t>(block.type) > 6)
    return Parse::skip;
  if (!decode_payload(payload, block)) {
    why = "block does not decode (bad size or value)";
    return Parse::bad;
  }
  return Parse::ok;
}

bool SessionReader::decode_payload(std::span<const uint8_t> payload, Block& block) {
  const std::size_t len = payload.size();
  switch (block.type) {
    case BlockType::raw:
      if (len < kRawPrefixBytes) return false;
      block.device_index = get_u16(payload.data());
      block.t_host_ns = static_cast<int64_t>(get_u64(payload.data() + 4));
      block.raw = payload.subspan(kRawPrefixBytes);
      return true;
    case BlockType::sample:
      return decode_sample(payload, block.sample);
    case BlockType::pose:
      return decode_pose(payload, block.pose);
    case BlockType::header_copy:
      block.raw = payload;
      return len >= kHeaderCopyPrefixBytes;
    case BlockType::clock:
      if (len != kClockPayloadBytes) return false;
      block.t_host_ns = static_cast<int64_t>(get_u64(payload.data()));
      block.t_unix_ns = static_cast<int64_t>(get_u64(payload.data() + 8));
      return true;
    default:
      return false;
  }
}

bool SessionReader::unpack(std::span<const uint8_t> payload, std::string& why) {
  if (payload.size() < kCompressedPrefixBytes) {
    why = "compressed block too short";
    return false;
  }
  const uint32_t want = get_u32(payload.data());
  if (want == 0 || want > kMaxGroupBytes) {
    why = "compressed block length " + std::to_string(want) + " exceeds the limit";
    return false;
  }
  if (!dctx_) dctx_ = ZSTD_createDCtx();
  group_.resize(kMaxGroupBytes);
  const std::size_t got = ZSTD_decompressDCtx(static_cast<ZSTD_DCtx*>(dctx_), group_.data(), want,
                                              payload.data() + kCompressedPrefixBytes,
                                              payload.size() - kCompressedPrefixBytes);
  if (ZSTD_isError(got) || got != want) {
    why = std::string("compressed block does not decompress (") +
          (ZSTD_isError(got) ? ZSTD_getErrorName(got) : "wrong length") + ")";
    return false;
  }
  unpacked_len_ = want;
  return true;
}

SessionReader::Parse SessionReader::next_inner(Block& block) {
  const uint8_t* p = group_.data() + group_pos_;
  const std::size_t left = group_len_ - group_pos_;
  if (left < kBlockHeaderBytes + kBlockTrailerBytes || get_u16(p) != kBlockSync) return Parse::bad;
  const uint32_t len = get_u32(p + 4);
  if (len > kMaxBlockPayload || kBlockHeaderBytes + len + kBlockTrailerBytes > left)
    return Parse::bad;
  const uint32_t crc = session::block_crc(0, p, static_cast<std::size_t>(kBlockHeaderBytes + len));
  if (static_cast<uint32_t>(crc) != get_u32(p + kBlockHeaderBytes + len)) return Parse::bad;
  block.offset = group_offset_;
  block.inner = static_cast<uint32_t>(group_pos_ + 1);
  block.type = static_cast<BlockType>(p[2]);
  group_pos_ += kBlockHeaderBytes + len + kBlockTrailerBytes;
  if (block.type == BlockType::compressed || block.type == BlockType::header_copy)
    return Parse::bad;  // never nested, never packed
  if (static_cast<uint8_t>(block.type) == 0 || static_cast<uint8_t>(block.type) > 6)
    return Parse::skip;
  return decode_payload({p + kBlockHeaderBytes, len}, block) ? Parse::ok : Parse::bad;
}

bool SessionReader::deliver(const Block& block) {
  const int64_t t = block_time(block);
  last_t_ns_ = t;
  if (damage_open_) {
    damaged_.back().t_after_ns = t;
    damage_open_ = false;
  }
  if (block.type == BlockType::clock) {  // absorbed: the offset for the blocks after it
    // A damaged or forged pair whose difference does not fit is no clock: the offset stays.
    int64_t offset = 0;
    if (!__builtin_sub_overflow(block.t_unix_ns, block.t_host_ns, &offset))
      unix_offset_ns_ = offset;
    return false;
  }
  return true;
}

uint64_t SessionReader::resync(uint64_t from, Block& scratch, uint64_t limit) {
  constexpr std::size_t kWindow = 64 * 1024;
  scan_.resize(kWindow);
  const uint8_t lo = static_cast<uint8_t>(kBlockSync & 0xff),
                hi = static_cast<uint8_t>(kBlockSync >> 8);
  uint64_t pos = from;
  while (pos + 1 < size_ && pos < limit) {
    const std::size_t n = read_at(pos, scan_.data(), kWindow);
    if (n < 2) break;
    for (std::size_t i = 0; i + 1 < n; ++i) {
      if (scan_[i] != lo || scan_[i + 1] != hi) continue;
      const uint64_t c = pos + i;
      if (c >= limit) return kNone;
      uint64_t block_end = 0;
      End kind = End::corrupt;
      std::string why;
      const Parse p = parse_at(c, scratch, block_end, kind, why);
      if (p == Parse::ok || p == Parse::skip) return c;
    }
    pos += n - 1;  // a marker split over the window's edge is seen in the next window
  }
  return kNone;
}

bool SessionReader::next(Block& block) {
  if (end_ != End::not_reached) return false;
  if (fd_ < 0 && memory_.empty()) return stop(End::corrupt, "no session open");
  for (;;) {
    if (group_pos_ < group_len_) {  // the blocks of an unpacked compressed block
      const Parse p = next_inner(block);
      if (p == Parse::skip) {
        ++unknown_blocks_;
        continue;
      }
      if (p == Parse::bad) {  // its content is damaged (the outer checksum held): lose the rest
        group_pos_ = group_len_ = 0;
        if (std::none_of(damaged_.begin(), damaged_.end(),
                         [&](const DamagedRange& d) { return d.begin == group_offset_; })) {
          damaged_.push_back({group_offset_, group_end_, last_t_ns_, -1,
                              "compressed block holds a damaged block at offset " +
                                  std::to_string(group_offset_)});
          damage_open_ = true;
        }
        continue;
      }
      if (deliver(block)) return true;
      continue;
    }
    uint64_t block_end = 0;
    End kind = End::corrupt;
    std::string why;
    const Parse p = parse_at(offset_, block, block_end, kind, why);
    if (p == Parse::eof) {
      if (damaged_.empty()) return stop(End::clean, "");
      return stop(End::corrupt, damaged_.front().reason);
    }
    if (p == Parse::skip) {
      ++unknown_blocks_;
      offset_ = block_end;
      continue;
    }
    if (p == Parse::ok) {
      offset_ = block_end;
      if (block.type == BlockType::header_copy) continue;
      if (block.type == BlockType::compressed) {
        ++compressed_blocks_;
        group_offset_ = block.offset;
        group_end_ = block_end;
        group_len_ = unpacked_len_;
        group_pos_ = 0;
        continue;
      }
      if (deliver(block)) return true;
      continue;
    }
    // Damage: resume at the next valid block, or end here.
    std::string reason = why + " at offset " + std::to_string(offset_);
    const uint64_t resume = resync(offset_ + 1, block, size_);
    if (resume == kNone) {
      if (kind == End::torn) return stop(damaged_.empty() ? End::torn : End::corrupt, reason);
      if (std::none_of(damaged_.begin(), damaged_.end(),
                       [&](const DamagedRange& d) { return d.begin == offset_; }))
        damaged_.push_back({offset_, size_, last_t_ns_, -1, reason});
      return stop(End::corrupt, std::move(reason));
    }
    if (std::none_of(damaged_.begin(), damaged_.end(),
                     [&](const DamagedRange& d) { return d.begin == offset_; })) {
      damaged_.push_back({offset_, resume, last_t_ns_, -1, std::move(reason)});
      damage_open_ = true;
    }
    offset_ = resume;
  }
}

}  // namespace mocap
