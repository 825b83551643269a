// DS4 / DualSense report parsers and calibration formulas (see playstation.hpp).
#include "mocap/drivers/playstation.hpp"

#include <cstdlib>

namespace mocap::playstation {

namespace {
int16_t le16(const uint8_t* p) {
  return static_cast<int16_t>(p[0] | (p[1] << 8));
}
}  // namespace

bool parse_input(Model m, std::span<const uint8_t> r, Input& out) {
  if (r.size() < kInputSize || r[0] != kInputUsb) return false;
  const uint8_t* p = r.data();
  if (m == Model::kDs4) {
    out.timestamp = static_cast<uint16_t>(le16(p + 10));
    for (int k = 0; k < 3; ++k)
      out.gyr[k] = le16(p + 13 + 2 * k), out.acc[k] = le16(p + 19 + 2 * k);
    out.seq = p[7] >> 2;
  } else {
    out.seq = p[7];
    for (int k = 0; k < 3; ++k)
      out.gyr[k] = le16(p + 16 + 2 * k), out.acc[k] = le16(p + 22 + 2 * k);
    out.timestamp = static_cast<uint32_t>(p[28]) | static_cast<uint32_t>(p[29]) << 8 |
                    static_cast<uint32_t>(p[30]) << 16 | static_cast<uint32_t>(p[31]) << 24;
  }
  return true;
}

bool parse_calibration(Model m, std::span<const uint8_t> r, Calibration& c) {
  if (r.empty()) return false;
  const uint8_t* p = r.data();
  bool bt_layout = false;
  if (m == Model::kDs4 && r[0] == kDs4CalibUsb && r.size() >= kDs4CalibUsbSize) {
    bt_layout = false;
  } else if (m == Model::kDs4 && r[0] == kCalibBt && r.size() >= kCalib41Size) {
    bt_layout = true;
  } else if (m == Model::kDualSense && r[0] == kCalibBt && r.size() >= kCalib41Size) {
    bt_layout = false;
  } else {
    return false;
  }
  for (int k = 0; k < 3; ++k)
    c.gyr_bias[k] = le16(p + 1 + 2 * k);
  if (!bt_layout) {  // pitch+ pitch- yaw+ yaw- roll+ roll-
    for (int k = 0; k < 3; ++k)
      c.gyr_plus[k] = le16(p + 7 + 4 * k), c.gyr_minus[k] = le16(p + 9 + 4 * k);
  } else {  // pitch+ yaw+ roll+ pitch- yaw- roll-
    for (int k = 0; k < 3; ++k)
      c.gyr_plus[k] = le16(p + 7 + 2 * k), c.gyr_minus[k] = le16(p + 13 + 2 * k);
  }
  c.speed_plus = le16(p + 19);
  c.speed_minus = le16(p + 21);
  for (int k = 0; k < 3; ++k)
    c.acc_plus[k] = le16(p + 23 + 4 * k), c.acc_minus[k] = le16(p + 25 + 4 * k);
  return true;
}

Scale default_scale() {
  Scale s;
  for (int k = 0; k < 3; ++k)
    s.gyr_dps_per_lsb[k] = 2048.0 / 32767, s.acc_g_per_lsb[k] = 4.0 / 32767;
  return s;
}

Scale scale_from(const Calibration& c) {
  Scale s = default_scale();
  const double speed_2x = static_cast<double>(c.speed_plus) + c.speed_minus;
  for (int k = 0; k < 3; ++k) {
    const double denom =
        std::abs(c.gyr_plus[k] - c.gyr_bias[k]) + std::abs(c.gyr_minus[k] - c.gyr_bias[k]);
    if (denom != 0 && speed_2x != 0) s.gyr_dps_per_lsb[k] = speed_2x / denom;
    const double range_2g = static_cast<double>(c.acc_plus[k]) - c.acc_minus[k];
    if (range_2g != 0) {
      s.acc_bias[k] = c.acc_plus[k] - range_2g / 2;
      s.acc_g_per_lsb[k] = 2.0 / range_2g;
    }
  }
  return s;
}

double tick_ns(Model m) {
  return m == Model::kDs4 ? 16000.0 / 3 : 1000.0 / 3;
}
uint64_t timestamp_modulus(Model m) {
  return m == Model::kDs4 ? 65536 : uint64_t{1} << 32;
}

}  // namespace mocap::playstation
