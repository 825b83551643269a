// SessionReader: header validation (magic, byte order, version, limits, CRC) and block
// iteration that stops at the first torn or corrupt block, classifying and locating it.
#include "mocap/session/session_reader.hpp"

#include <sys/stat.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace mocap {

using namespace session;

SessionReader::~SessionReader() {
  if (file_) std::fclose(file_);
}

bool SessionReader::open(const std::string& path, std::string* error) {
  if (file_) std::fclose(file_);
  file_ = std::fopen(path.c_str(), "rb");
  if (!file_) {
    if (error) *error = "cannot open session file '" + path + "': " + std::strerror(errno);
    return false;
  }
  struct stat st {};
  size_ = ::fstat(fileno(file_), &st) == 0 ? static_cast<uint64_t>(st.st_size) : 0;
  return read_header("'" + path + "'", error);
}

bool SessionReader::open_bytes(std::span<const uint8_t> bytes, std::string* error) {
  if (file_) std::fclose(file_);
  file_ = nullptr;
  memory_.assign(bytes.begin(), bytes.end());
  size_ = memory_.size();
  return read_header("session data", error);
}

namespace {
/// Reads up to n bytes at offset from the file (sequentially) or memory; returns the count.
std::size_t read_at(std::FILE* f, const std::vector<uint8_t>& mem, uint64_t offset, uint8_t* dst,
                    std::size_t n) {
  if (f) return std::fread(dst, 1, n, f);
  if (offset >= mem.size()) return 0;
  const std::size_t got = std::min<std::size_t>(n, mem.size() - offset);
  std::memcpy(dst, mem.data() + offset, got);
  return got;
}
}  // namespace

bool SessionReader::read_header(const std::string& name, std::string* error) {
  auto fail = [&](const std::string& m) {
    if (error) *error = name + ": " + m;
    return false;
  };
  offset_ = 0;
  end_ = End::not_reached;
  tail_reason_.clear();
  unknown_blocks_ = 0;
  uint8_t fixed[20];
  const std::size_t got = read_at(file_, memory_, 0, fixed, sizeof fixed);
  if (got < sizeof kMagic || std::memcmp(fixed, kMagic, sizeof kMagic) != 0)
    return fail("not a mocap session file (no MOCAPSES signature)");
  if (got < sizeof fixed) return fail("session header truncated");
  const uint32_t version = get_u32(fixed + 8);
  const uint32_t endian = get_u32(fixed + 12);
  if (endian != kEndianTag)
    return fail("unknown byte-order tag 0x" + [&] {
      char b[16];
      std::snprintf(b, sizeof b, "%08x", endian);
      return std::string(b);
    }() + " (expected little-endian 0x01020304)");
  if (version != kVersion)
    return fail("session format version " + std::to_string(version) +
                " is not supported (this build reads version " + std::to_string(kVersion) + ")");
  const uint32_t len = get_u32(fixed + 16);
  if (len > kMaxHeaderBytes)
    return fail("header length " + std::to_string(len) + " exceeds the 4 MiB limit");
  if (len + 24ull > size_) return fail("session header truncated");
  std::vector<uint8_t> buf(sizeof fixed + len + 4);
  std::memcpy(buf.data(), fixed, sizeof fixed);
  if (read_at(file_, memory_, sizeof fixed, buf.data() + sizeof fixed, len + 4) != len + 4)
    return fail("session header truncated");
  const auto crc = crc32(0L, buf.data(), static_cast<uInt>(buf.size() - 4));
  if (static_cast<uint32_t>(crc) != get_u32(buf.data() + buf.size() - 4))
    return fail("session header checksum mismatch (file damaged)");
  std::string msg;
  if (!decode_header_payload({buf.data() + sizeof fixed, len}, header_, &msg)) return fail(msg);
  offset_ = header_bytes_ = buf.size();
  payload_.resize(kMaxBlockPayload + kBlockTrailerBytes);
  return true;
}

bool SessionReader::stop(End end, std::string reason) {
  end_ = end;
  tail_reason_ = std::move(reason);
  return false;
}

bool SessionReader::seek(uint64_t offset) {
  if (offset < header_bytes_ || offset > size_) return false;
  // Files are read sequentially (read_at ignores the offset for them): move the stream too.
  if (file_ && ::fseeko(file_, static_cast<off_t>(offset), SEEK_SET) != 0) return false;
  offset_ = offset;
  end_ = End::not_reached;
  tail_reason_.clear();
  return true;
}

bool SessionReader::next(Block& block) {
  if (end_ != End::not_reached) return false;
  if (!file_ && memory_.empty()) return stop(End::corrupt, "no session open");
  for (;;) {
    // Built only when reading stops: a string per block would cost an allocation per sample.
    const auto at = [this] { return " at offset " + std::to_string(offset_); };
    uint8_t hdr[kBlockHeaderBytes];
    const std::size_t got = read_at(file_, memory_, offset_, hdr, sizeof hdr);
    if (got == 0) return stop(End::clean, "");
    if (got < sizeof hdr) return stop(End::torn, "incomplete block header" + at());
    if (get_u16(hdr) != kBlockSync) {
      const bool zeros = std::all_of(hdr, hdr + sizeof hdr, [](uint8_t b) { return b == 0; });
      return stop(zeros ? End::torn : End::corrupt,
                  (zeros ? "zero-filled tail" : "no block marker") + at());
    }
    const uint32_t len = get_u32(hdr + 4);
    if (len > kMaxBlockPayload)
      return stop(End::corrupt,
                  "block length " + std::to_string(len) + " exceeds the limit" + at());
    const std::size_t want = len + kBlockTrailerBytes;
    const std::size_t have = read_at(file_, memory_, offset_ + sizeof hdr, payload_.data(), want);
    if (have < want)
      return stop(End::torn, "last block truncated (" + std::to_string(have) + " of " +
                                 std::to_string(want) + " bytes)" + at());
    uLong crc = crc32(0L, hdr, sizeof hdr);
    crc = crc32(crc, payload_.data(), len);
    const uint64_t block_end = offset_ + sizeof hdr + want;
    if (static_cast<uint32_t>(crc) != get_u32(payload_.data() + len))
      return stop(
          block_end == size_ ? End::torn : End::corrupt,
          std::string(block_end == size_ ? "last block" : "block") + " fails its checksum" + at());
    const std::span<const uint8_t> payload(payload_.data(), len);
    block.offset = offset_;
    block.type = static_cast<BlockType>(hdr[2]);
    bool ok = true;
    switch (block.type) {
      case BlockType::raw:
        ok = len >= kRawPrefixBytes;
        if (ok) {
          block.device_index = get_u16(payload.data());
          block.t_host_ns = static_cast<int64_t>(get_u64(payload.data() + 4));
          block.raw = payload.subspan(kRawPrefixBytes);
        }
        break;
      case BlockType::sample:
        ok = decode_sample(payload, block.sample);
        break;
      case BlockType::pose:
        ok = decode_pose(payload, block.pose);
        break;
      default:
        ++unknown_blocks_;
        offset_ = block_end;
        continue;
    }
    if (!ok) return stop(End::corrupt, "block does not decode (bad size or value)" + at());
    offset_ = block_end;
    return true;
  }
}

}  // namespace mocap
