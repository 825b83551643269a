// libFuzzer target for SessionReader. Even first byte: the input is read as a session file as
// is (header, framing, limits). Odd first byte: the input is cut into blocks that get valid
// framing and CRCs behind a valid header, so the payload decoders are reached too; a chunk of
// type 5 (compressed) is itself framed into blocks and zstd-compressed, so the blocks inside a
// compressed block are reached as well. The reader
// must never crash, over-allocate, stop without saying why, or yield a non-finite pose.
#include <zlib.h>
#include <zstd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "mocap/session/session_reader.hpp"

namespace ses = mocap::session;

namespace {

/// Cuts data into blocks: [type, len lo, len hi, payload...]; appends them with valid framing.
void frame_blocks(const uint8_t* data, size_t size, std::vector<uint8_t>& out, bool nested) {
  size_t i = 0;
  while (i + 3 <= size) {
    const uint8_t type = data[i] % 8;
    const size_t len = std::min<size_t>(data[i + 1] | (data[i + 2] << 8), size - i - 3);
    i += 3;
    std::vector<uint8_t> payload(data + i, data + i + len);
    if (type == 5 && !nested) {  // compressed: the chunk framed into blocks, then packed
      std::vector<uint8_t> inner;
      frame_blocks(data + i, len, inner, true);
      payload.assign(4 + ZSTD_compressBound(inner.size()), 0);
      const size_t c =
          ZSTD_compress(payload.data() + 4, payload.size() - 4, inner.data(), inner.size(), 1);
      if (ZSTD_isError(c)) std::abort();
      ses::put_u32(payload.data(), static_cast<uint32_t>(inner.size()));
      payload.resize(4 + c);
    }
    uint8_t hdr[ses::kBlockHeaderBytes];
    ses::encode_block_header(static_cast<ses::BlockType>(type),
                             static_cast<uint32_t>(payload.size()), hdr);
    uLong crc =
        crc32(crc32(0L, hdr, sizeof hdr), payload.data(), static_cast<uInt>(payload.size()));
    out.insert(out.end(), hdr, hdr + sizeof hdr);
    out.insert(out.end(), payload.begin(), payload.end());
    uint8_t c[4];
    ses::put_u32(c, static_cast<uint32_t>(crc));
    out.insert(out.end(), c, c + 4);
    i += len;
  }
}

std::vector<uint8_t> framed(const uint8_t* data, size_t size) {
  std::vector<uint8_t> out;
  ses::SessionHeader h;
  h.sensors = {{"a", "sim", 0, 0}};
  std::string err;
  ses::encode_file_header(h, out, &err);
  frame_blocks(data, size, out, false);
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<uint8_t> bytes;
  if (size > 0 && (data[0] & 1))
    bytes = framed(data + 1, size - 1);
  else
    bytes.assign(data, data + size);
  mocap::SessionReader reader;
  std::string error;
  if (!reader.open_bytes(bytes, &error)) {
    if (error.empty()) std::abort();
    return 0;
  }
  mocap::SessionReader::Block block;
  while (reader.next(block)) {
    if (block.type == ses::BlockType::pose) {
      for (const auto& q : block.pose.q_earth_segment)
        for (float v : q)
          if (!std::isfinite(v)) std::abort();
    }
  }
  if (reader.end() == mocap::SessionReader::End::not_reached) std::abort();
  if (reader.end() != mocap::SessionReader::End::clean && reader.tail_reason().empty())
    std::abort();
  return 0;
}
