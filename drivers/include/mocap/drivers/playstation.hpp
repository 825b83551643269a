// Sony DualShock 4 and DualSense over USB HID: input-report and calibration-feature-report
// parsers (raw integers out) and the Linux hid-playstation calibration formulas.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace mocap::playstation {

enum class Model { kDs4, kDualSense };

constexpr uint8_t kInputUsb = 0x01;     ///< both models, 64 bytes
constexpr uint8_t kDs4CalibUsb = 0x02;  ///< 37 bytes
constexpr uint8_t kCalibBt = 0x05;      ///< DS4 over BT/dongle and DualSense: 41 bytes
constexpr std::size_t kInputSize = 64, kDs4CalibUsbSize = 37, kCalib41Size = 41;

/// Sensor fields of one input report, as sent.
struct Input {
  std::array<int16_t, 3> gyr{}, acc{};
  uint32_t timestamp = 0;  ///< DS4: uint16, 16/3 us ticks; DualSense: uint32, 1/3 us ticks
  uint8_t seq = 0;         ///< DualSense sequence number (DS4: frame counter, upper 6 bits)
};
bool parse_input(Model m, std::span<const uint8_t> report, Input& out);

struct Calibration {
  std::array<int16_t, 3> gyr_bias{}, gyr_plus{}, gyr_minus{};
  int16_t speed_plus = 0, speed_minus = 0;
  std::array<int16_t, 3> acc_plus{}, acc_minus{};
};
/// DS4: report 0x02 (USB layout) or 0x05 (Bluetooth layout, plus/minus interleaved differently);
/// DualSense: report 0x05 (USB layout). False if the id or size does not fit.
bool parse_calibration(Model m, std::span<const uint8_t> report, Calibration& out);

/// Per-axis conversion derived from a calibration (kernel formulas; fixed fallbacks when a
/// denominator is zero, as on clones): dps = raw * gyr_dps_per_lsb; g = (raw - acc_bias) *
/// acc_g_per_lsb.
struct Scale {
  std::array<double, 3> gyr_dps_per_lsb{}, acc_g_per_lsb{}, acc_bias{};
};
Scale scale_from(const Calibration& c);
Scale default_scale();

/// Timestamp tick in ns (fractional) and its wrap modulus.
double tick_ns(Model m);
uint64_t timestamp_modulus(Model m);

}  // namespace mocap::playstation
