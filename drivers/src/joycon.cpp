// Joy-Con / Pro Controller report parsers, host commands and calibration (see joycon.hpp).
#include "mocap/drivers/joycon.hpp"

#include <algorithm>

namespace mocap::joycon {

namespace {
int16_t le16(const uint8_t* p) {
  return static_cast<int16_t>(p[0] | (p[1] << 8));
}
}  // namespace

bool parse_full(std::span<const uint8_t> r, FullReport& out) {
  if (r.size() < 49 || r[0] != kInputFull) return false;
  out.timer = r[1];
  for (int i = 0; i < 3; ++i) {
    const uint8_t* p = r.data() + 13 + 12 * i;
    for (int k = 0; k < 3; ++k)
      out.imu[i].acc[k] = le16(p + 2 * k), out.imu[i].gyr[k] = le16(p + 6 + 2 * k);
  }
  return true;
}

bool parse_reply(std::span<const uint8_t> r, Reply& out) {
  if (r.size() < 15 || r[0] != kInputReply) return false;
  out.ack = r[13];
  out.subcmd = r[14];
  out.data = r.subspan(15);
  return true;
}

Calibration parse_calibration(std::span<const uint8_t, kImuCalibSize> b) {
  Calibration c;
  for (int k = 0; k < 3; ++k) {
    c.acc_origin[k] = le16(&b[2 * k]);
    c.acc_sens[k] = le16(&b[6 + 2 * k]);
    c.gyr_offset[k] = le16(&b[12 + 2 * k]);
    c.gyr_sens[k] = le16(&b[18 + 2 * k]);
  }
  return c;
}

bool parse_spi_reply(const Reply& r, SpiData& out) {
  if (r.subcmd != kSubSpiRead || r.data.size() < 5) return false;
  out.address =
      r.data[0] | r.data[1] << 8 | r.data[2] << 16 | static_cast<uint32_t>(r.data[3]) << 24;
  const std::size_t len = std::min<std::size_t>(r.data[4], r.data.size() - 5);
  out.bytes = r.data.subspan(5, len);
  return true;
}

void encode_calibration(const Calibration& c, std::span<uint8_t, kImuCalibSize> out) {
  auto put = [&](int off, int16_t v) {
    out[off] = static_cast<uint8_t>(v & 0xFF);
    out[off + 1] = static_cast<uint8_t>((static_cast<uint16_t>(v) >> 8) & 0xFF);
  };
  for (int k = 0; k < 3; ++k) {
    put(2 * k, c.acc_origin[k]);
    put(6 + 2 * k, c.acc_sens[k]);
    put(12 + 2 * k, c.gyr_offset[k]);
    put(18 + 2 * k, c.gyr_sens[k]);
  }
}

double acc_g(const Calibration& c, int k, int16_t raw) {
  int d = c.acc_sens[k] - c.acc_origin[k];
  if (d == 0) d = 1;
  return static_cast<double>(raw) * c.acc_sens[k] / d / 4096.0;
}

double gyr_dps(const Calibration& c, int k, int16_t raw) {
  int d = c.gyr_sens[k] - c.gyr_offset[k];
  if (d == 0) d = 1;
  return (static_cast<double>(raw) - c.gyr_offset[k]) * c.gyr_sens[k] / d / 14.247;
}

std::vector<uint8_t> subcommand(uint8_t counter, uint8_t id, std::span<const uint8_t> args) {
  std::vector<uint8_t> r = {kOutputSubcmd,
                            static_cast<uint8_t>(counter & 0x0F),
                            0x00,
                            0x01,
                            0x40,
                            0x40,
                            0x00,
                            0x01,
                            0x40,
                            0x40,
                            id};
  for (uint8_t b : args)
    r.push_back(b);
  return r;
}

std::vector<uint8_t> spi_read(uint8_t counter, uint32_t a, uint8_t length) {
  const uint8_t args[5] = {static_cast<uint8_t>(a), static_cast<uint8_t>(a >> 8),
                           static_cast<uint8_t>(a >> 16), static_cast<uint8_t>(a >> 24), length};
  return subcommand(counter, kSubSpiRead, args);
}

}  // namespace mocap::joycon
