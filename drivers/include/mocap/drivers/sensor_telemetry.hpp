// What a sensor reports about itself beside its samples: battery, radio signal, temperature and
// its identity (board, IMU, MCU, firmware, address). Declared once here; a decoder fills it
// from the device's own packets (SlimeVR: handshake, battery, signal strength, temperature;
// its HID receiver: device info, status, runtime) and hands it to SampleSink::on_telemetry when
// a value changes; the daemon keeps the newest per sensor for its status report. Fixed size,
// no allocation: it crosses from a device thread under a short lock.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string_view>

namespace mocap {

struct SensorTelemetry {
  static constexpr float kUnknown = std::numeric_limits<float>::quiet_NaN();

  float battery_fraction = kUnknown;   ///< charge, 0..1
  float battery_v = kUnknown;          ///< battery voltage, V
  float battery_runtime_s = kUnknown;  ///< the device's estimate of the time left on battery, s
  float rssi_dbm = kUnknown;           ///< received signal strength, dBm (WiFi or the receiver's)
  float temperature_c = kUnknown;      ///< IMU temperature, degrees C
  float packet_loss = kUnknown;        ///< fraction of radio packets lost (HID receiver), 0..1
  char board[32] = {};                 ///< board name ("SlimeVR", "board 42" if unknown)
  char imu[16] = {};                   ///< IMU name ("BMI270", ...)
  char mcu[16] = {};                   ///< MCU name ("ESP8266", ...)
  char firmware[48] = {};              ///< firmware version (and build date when sent)
  char address[24] = {};               ///< hardware address (MAC) as text

  static bool known(float v) { return !std::isnan(v); }
  /// Copies text into one of the fields above, truncated and NUL-terminated.
  template <std::size_t N>
  static void set(char (&field)[N], std::string_view text) {
    const std::size_t n = text.size() < N - 1 ? text.size() : N - 1;
    std::memcpy(field, text.data(), n);
    std::memset(field + n, 0, N - n);
  }
  bool operator==(const SensorTelemetry& o) const {
    const auto same = [](float a, float b) { return a == b || (std::isnan(a) && std::isnan(b)); };
    return same(battery_fraction, o.battery_fraction) && same(battery_v, o.battery_v) &&
           same(battery_runtime_s, o.battery_runtime_s) && same(rssi_dbm, o.rssi_dbm) &&
           same(temperature_c, o.temperature_c) && same(packet_loss, o.packet_loss) &&
           std::memcmp(board, o.board, sizeof board) == 0 &&
           std::memcmp(imu, o.imu, sizeof imu) == 0 && std::memcmp(mcu, o.mcu, sizeof mcu) == 0 &&
           std::memcmp(firmware, o.firmware, sizeof firmware) == 0 &&
           std::memcmp(address, o.address, sizeof address) == 0;
  }
  /// Whether any field is set (a device that reports nothing has none).
  bool any() const { return !(*this == SensorTelemetry{}); }
};

}  // namespace mocap
