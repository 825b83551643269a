// WitMotion 0x55-packet framer, encoder and configuration commands (see witmotion.hpp).
#include "mocap/drivers/witmotion.hpp"

#include <cmath>
#include <cstring>

namespace mocap::witmotion {

bool valid_type(uint8_t type) {
  return (type >= 0x50 && type <= 0x5A) || type == kRegReply;
}

static uint8_t sum(const uint8_t* p, std::size_t n) {
  unsigned s = 0;
  for (std::size_t i = 0; i < n; ++i)
    s += p[i];
  return static_cast<uint8_t>(s);
}

void Framer::discard(std::size_t n) {
  if (in_sync_) ++resyncs;
  in_sync_ = false;
  std::memmove(buf_.data(), buf_.data() + n, n_ - n);
  n_ -= n;
  // Drop until a plausible packet start remains.
  std::size_t skip = 0;
  while (skip < n_ && (buf_[skip] != kHeader || (skip + 1 < n_ && !valid_type(buf_[skip + 1]))))
    ++skip;
  std::memmove(buf_.data(), buf_.data() + skip, n_ - skip);
  n_ -= skip;
}

std::size_t Framer::consume(std::span<const uint8_t> in, Packet& out, bool& got) {
  got = false;
  std::size_t i = 0;
  while (i < in.size()) {
    const uint8_t b = in[i++];
    if (n_ == 0 && b != kHeader) {
      if (in_sync_) ++resyncs;
      in_sync_ = false;
      continue;
    }
    buf_[n_++] = b;
    if (n_ == 2 && !valid_type(b)) {
      discard(1);
      continue;
    }
    if (n_ < kPacketSize) continue;
    if (sum(buf_.data(), kPacketSize - 1) != buf_[kPacketSize - 1]) {
      ++checksum_errors;
      discard(1);
      continue;
    }
    out.type = buf_[1];
    for (int k = 0; k < 4; ++k)
      out.d[k] = static_cast<int16_t>(buf_[2 + 2 * k] | (buf_[3 + 2 * k] << 8));
    n_ = 0;
    in_sync_ = true;
    ++frames;
    got = true;
    return i;
  }
  return i;
}

void encode(const Packet& p, std::vector<uint8_t>& out) {
  uint8_t b[kPacketSize];
  b[0] = kHeader;
  b[1] = p.type;
  for (int k = 0; k < 4; ++k) {
    const auto u = static_cast<uint16_t>(p.d[k]);
    b[2 + 2 * k] = static_cast<uint8_t>(u & 0xFF);
    b[3 + 2 * k] = static_cast<uint8_t>(u >> 8);
  }
  b[10] = sum(b, 10);
  out.insert(out.end(), b, b + kPacketSize);
}

std::array<uint8_t, 5> command(uint8_t reg, uint16_t value) {
  return {0xFF, 0xAA, reg, static_cast<uint8_t>(value & 0xFF), static_cast<uint8_t>(value >> 8)};
}

static constexpr double kRates[] = {0, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100, 125, 200};
uint8_t rate_code(double hz) {
  uint8_t best = 0x06;
  double best_err = 1e9;
  for (uint8_t c = 1; c <= 0x0B; ++c) {
    if (c == 0x0A) continue;  // 125 Hz exists on the WT931 only
    const double err = std::fabs(std::log(kRates[c] / hz));
    if (err < best_err) best_err = err, best = c;
  }
  return best;
}
double rate_hz(uint8_t code) {
  return code >= 1 && code <= 0x0B ? kRates[code] : 0;
}

static constexpr int kBauds[] = {0,     4800,   9600,   19200,  38400,
                                 57600, 115200, 230400, 460800, 921600};
uint8_t baud_code(int baud) {
  for (uint8_t c = 1; c <= 9; ++c)
    if (kBauds[c] == baud) return c;
  return 0;
}
int baud_from_code(uint8_t code) {
  return code >= 1 && code <= 9 ? kBauds[code] : 0;
}

}  // namespace mocap::witmotion
