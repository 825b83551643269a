// Host commands a WitMotion device gets after opening: unlock, output content (time, acc, gyro,
// angle, mag, quaternion), return rate. Not saved to flash (the device reverts on power-cycle).
#include "mocap/drivers/witmotion.hpp"
#include "protocols.hpp"

namespace mocap {

std::vector<SetupStep> witmotion_setup(const DeviceSpec& spec) {
  using namespace witmotion;
  auto write = [](std::array<uint8_t, 5> cmd, const char* what) {
    SetupStep s;
    s.bytes.assign(cmd.begin(), cmd.end());
    s.timeout_ms = 30;  // the vendor tools leave a short gap between commands
    s.what = what;
    return s;
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
  return steps;
}

}  // namespace mocap
