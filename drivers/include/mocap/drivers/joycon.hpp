// Nintendo Joy-Con / Pro Controller over USB HID: the full-mode input report (0x30, three IMU
// samples), subcommand replies (0x21), USB command replies (0x81), the host commands (USB
// handshake, subcommands incl. SPI reads) and the factory IMU calibration.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace mocap::joycon {

constexpr uint8_t kInputFull = 0x30, kInputReply = 0x21, kUsbReply = 0x81;
constexpr uint8_t kOutputSubcmd = 0x01, kUsbCmd = 0x80;
constexpr uint8_t kSubSpiRead = 0x10, kSubReportMode = 0x03, kSubEnableImu = 0x40;
constexpr uint32_t kSpiImuFactoryCalib = 0x6020;
/// User IMU calibration (written by the console's "calibrate motion controls"): magic B2 A1 at
/// 0x8026, the 24 calibration bytes at 0x8028 when the magic is there (Linux hid-nintendo, SDL
/// use it before the factory one). One SPI read of kImuUserReadSize at 0x8026 gets both.
constexpr uint32_t kSpiImuUserCalib = 0x8026;
constexpr uint8_t kUserCalibMagic0 = 0xB2, kUserCalibMagic1 = 0xA1;
constexpr std::size_t kImuCalibSize = 24, kReportSize = 64;
constexpr std::size_t kImuUserReadSize = 2 + kImuCalibSize;
constexpr int64_t kImuSpacingNs = 5'000'000;  ///< the three samples of a report are ~5 ms apart

struct ImuRaw {
  std::array<int16_t, 3> acc{}, gyr{};
};
struct FullReport {
  uint8_t timer = 0;
  std::array<ImuRaw, 3> imu{};  ///< oldest first
};
bool parse_full(std::span<const uint8_t> report, FullReport& out);

/// A 0x21 subcommand reply: ack byte, echoed subcommand id, reply data.
struct Reply {
  uint8_t ack = 0, subcmd = 0;
  std::span<const uint8_t> data;
};
bool parse_reply(std::span<const uint8_t> report, Reply& out);

/// Factory calibration: acc origin/sensitivity, gyro offset/sensitivity (int16 x 3 each).
struct Calibration {
  std::array<int16_t, 3> acc_origin{0, 0, 0}, acc_sens{16384, 16384, 16384};
  std::array<int16_t, 3> gyr_offset{0, 0, 0}, gyr_sens{13371, 13371, 13371};
};
Calibration parse_calibration(std::span<const uint8_t, kImuCalibSize> bytes);
/// An SPI read reply's data (address LE32, length, bytes): the address and the bytes read.
struct SpiData {
  uint32_t address = 0;
  std::span<const uint8_t> bytes;
};
bool parse_spi_reply(const Reply& r, SpiData& out);
void encode_calibration(const Calibration& c, std::span<uint8_t, kImuCalibSize> out);
/// Linux hid-nintendo conversion: g = raw * sens / (sens - origin) / 4096;
/// dps = (raw - offset) * sens / (sens - offset) / 14.247 (zero divisors replaced by 1).
double acc_g(const Calibration& c, int axis, int16_t raw);
double gyr_dps(const Calibration& c, int axis, int16_t raw);

/// Output report 0x01: counter, neutral rumble, subcommand id and arguments.
std::vector<uint8_t> subcommand(uint8_t counter, uint8_t id, std::span<const uint8_t> args);
std::vector<uint8_t> spi_read(uint8_t counter, uint32_t address, uint8_t length);

}  // namespace mocap::joycon
