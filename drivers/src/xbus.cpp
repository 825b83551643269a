// Xbus framer, MTData2 parser and encoder (see xbus.hpp).
#include "mocap/drivers/xbus.hpp"

#include <algorithm>
#include <bit>
#include <cstring>

namespace mocap::xbus {

void Framer::drop(std::size_t k) {
  front_ += k;
  // Skip to the next preamble.
  std::size_t skip = 0;
  while (front_ + skip < n_ && buf_[front_ + skip] != kPreamble)
    ++skip;
  front_ += skip;
}

std::size_t Framer::consume(std::span<const uint8_t> in, Message& out, bool& got) {
  got = false;
  if (front_ > 0) {
    std::memmove(buf_.data(), buf_.data() + front_, n_ - front_);
    n_ -= front_;
    front_ = 0;
  }
  const std::size_t take = std::min(in.size(), buf_.size() - n_);
  std::memcpy(buf_.data() + n_, in.data(), take);
  n_ += take;
  for (;;) {
    std::size_t skip = 0;
    while (front_ + skip < n_ && buf_[front_ + skip] != kPreamble)
      ++skip;
    if (skip > 0) {
      front_ += skip;
      if (in_sync_) ++resyncs;
      in_sync_ = false;
    }
    const uint8_t* p = buf_.data() + front_;
    const std::size_t avail = n_ - front_;
    if (avail < 4) break;
    std::size_t len = p[3], hdr = 4;
    if (len == 0xFF) {
      if (avail < 6) break;
      len = static_cast<std::size_t>(p[4] << 8 | p[5]);
      hdr = 6;
    }
    if (len > kMaxPayload) {
      if (in_sync_) ++resyncs;
      in_sync_ = false;
      drop(1);
      continue;
    }
    const std::size_t total = hdr + len + 1;
    if (avail < total) break;
    uint8_t sum = 0;
    for (std::size_t i = 1; i < total; ++i)
      sum = static_cast<uint8_t>(sum + p[i]);
    if (sum != 0) {
      ++checksum_errors;
      in_sync_ = false;
      drop(1);
      continue;
    }
    out.bid = p[1];
    out.mid = p[2];
    out.data = std::span<const uint8_t>(p + hdr, len);
    front_ += total;
    ++frames;
    in_sync_ = true;
    got = true;
    break;
  }
  if (front_ == n_) front_ = n_ = 0;  // nothing buffered: keep `out.data` valid (no move)
  return take;
}

namespace {
uint32_t be32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) << 24 | static_cast<uint32_t>(p[1]) << 16 |
         static_cast<uint32_t>(p[2]) << 8 | p[3];
}
/// One value of `fmt` (0 float32, 1 fixed 12.20, 2 fixed 16.32, 3 float64) at p.
double value(const uint8_t* p, int fmt) {
  switch (fmt) {
    case 0:
      return std::bit_cast<float>(be32(p));
    case 1:
      return static_cast<int32_t>(be32(p)) / 1048576.0;
    case 2: {
      const int16_t hi = static_cast<int16_t>(p[4] << 8 | p[5]);
      return (static_cast<double>(hi) * 4294967296.0 + be32(p)) / 4294967296.0;
    }
    default: {
      const uint64_t u = static_cast<uint64_t>(be32(p)) << 32 | be32(p + 4);
      return std::bit_cast<double>(u);
    }
  }
}
constexpr std::size_t kFmtSize[4] = {4, 4, 6, 8};
}  // namespace

bool parse_mtdata2(std::span<const uint8_t> d, MtData2& out) {
  out = MtData2{};
  std::size_t i = 0;
  while (i < d.size()) {
    if (d.size() - i < 3) return false;
    const uint16_t id = static_cast<uint16_t>(d[i] << 8 | d[i + 1]);
    const std::size_t size = d[i + 2];
    i += 3;
    if (d.size() - i < size) return false;
    const uint8_t* p = d.data() + i;
    const int fmt = id & 0x3;
    const uint16_t type = id & 0xFFF0;
    auto vec = [&](std::size_t n, double* dst) {
      if (size != n * kFmtSize[fmt]) return false;
      for (std::size_t k = 0; k < n; ++k)
        dst[k] = value(p + k * kFmtSize[fmt], fmt);
      return true;
    };
    switch (type) {
      case kPacketCounter & 0xFFF0:
        if (size != 2) return false;
        out.counter = static_cast<uint16_t>(p[0] << 8 | p[1]);
        out.has_counter = true;
        break;
      case kSampleTimeFine & 0xFFF0:
        if (size != 4) return false;
        out.time_fine = be32(p);
        out.has_time = true;
        break;
      case kQuaternion & 0xFFF0:
        if (!vec(4, out.quat.data())) return false;
        out.quat_coord = id & 0x0C;
        out.has_quat = true;
        break;
      case kAcceleration & 0xFFF0:
        if (!vec(3, out.acc.data())) return false;
        out.has_acc = true;
        break;
      case kRateOfTurn & 0xFFF0:
        if (!vec(3, out.gyr.data())) return false;
        out.has_gyr = true;
        break;
      case kMagneticField & 0xFFF0:
        if (!vec(3, out.mag.data())) return false;
        out.has_mag = true;
        break;
      default:
        break;  // skipped by its size
    }
    i += size;
  }
  return true;
}

void encode(uint8_t mid, std::span<const uint8_t> payload, std::vector<uint8_t>& out) {
  const std::size_t start = out.size();
  out.push_back(kPreamble);
  out.push_back(kBusMaster);
  out.push_back(mid);
  if (payload.size() < 0xFF) {
    out.push_back(static_cast<uint8_t>(payload.size()));
  } else {
    out.push_back(0xFF);
    out.push_back(static_cast<uint8_t>(payload.size() >> 8));
    out.push_back(static_cast<uint8_t>(payload.size() & 0xFF));
  }
  out.insert(out.end(), payload.begin(), payload.end());
  uint8_t sum = 0;
  for (std::size_t i = start + 1; i < out.size(); ++i)
    sum = static_cast<uint8_t>(sum + out[i]);
  out.push_back(static_cast<uint8_t>(-sum));
}

void put_floats(uint16_t id, std::span<const double> v, std::vector<uint8_t>& payload) {
  payload.push_back(static_cast<uint8_t>(id >> 8));
  payload.push_back(static_cast<uint8_t>(id & 0xFF));
  payload.push_back(static_cast<uint8_t>(v.size() * 4));
  for (double x : v) {
    const uint32_t u = std::bit_cast<uint32_t>(static_cast<float>(x));
    for (int s = 24; s >= 0; s -= 8)
      payload.push_back(static_cast<uint8_t>(u >> s));
  }
}

}  // namespace mocap::xbus
