// Host commands a WitMotion device gets after opening: unlock, output content (time, acc, gyro,
// angle, mag, quaternion), return rate. Not saved to flash (the device reverts on power-cycle).
#include <stdexcept>
#include <string>

#include "mocap/drivers/witmotion.hpp"
#include "protocols.hpp"

namespace mocap {

std::vector<SetupStep> witmotion_setup(const DeviceSpec& spec) {
  using namespace witmotion;
  auto write = [](std::array<uint8_t, 5> cmd, const char* what) {
    // 30 ms: the vendor tools leave a short gap between commands.
    return SetupStep{.bytes = {cmd.begin(), cmd.end()}, .timeout_ms = 30, .what = what};
  };
  std::vector<SetupStep> steps;
  if (option_string(spec, "configure", "1") == "0") return steps;
  const uint16_t rsw = rsw_bit(kTime) | rsw_bit(kAcc) | rsw_bit(kGyr) | rsw_bit(kAngle) |
                       rsw_bit(kMag) | rsw_bit(kQuat);
  steps.push_back(write(command(kRegKey, kUnlockKey), "unlock"));
  steps.push_back(write(command(kRegRsw, rsw), "set output content"));
  if (spec.rate_hz > 0) {
    steps.push_back(write(command(kRegKey, kUnlockKey), "unlock"));
    steps.push_back(write(command(kRegRate, rate_code(spec.rate_hz)), "set return rate"));
  }
  // options.device_baud: switch the device (and then the host side) to another baud rate,
  // e.g. 115200 for 100 Hz output. Saved to flash so the device keeps it after power-cycling.
  const int device_baud = static_cast<int>(option_double(spec, "device_baud", 0));
  if (device_baud > 0) {
    const uint8_t code = baud_code(device_baud);
    if (code == 0)
      throw std::invalid_argument("device " + spec.name + ": device_baud " +
                                  std::to_string(device_baud) +
                                  " is not a WitMotion rate (4800..921600)");
    steps.push_back(write(command(kRegKey, kUnlockKey), "unlock"));
    steps.push_back(write(command(kRegBaud, code), "set baud"));
    SetupStep follow;
    follow.kind = SetupStep::kSetBaud;
    follow.baud = device_baud;
    follow.timeout_ms = 50;
    follow.what = "follow the new baud";
    steps.push_back(follow);
    steps.push_back(write(command(kRegKey, kUnlockKey), "unlock"));
    steps.push_back(write(command(kRegSave, 0), "save"));
  }
  return steps;
}

}  // namespace mocap
