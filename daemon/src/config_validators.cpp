// The loader's cross-module checks: a sensor's driver and options must be accepted by the
// drivers' make_decoder (the filter's keys come from its own table: config_keys.hpp).
#include <stdexcept>

#include "mocap/daemon/config.hpp"
#include "mocap/daemon/daemon.hpp"
#include "mocap/drivers/device.hpp"

namespace mocap::daemon {

const ConfigValidators& default_validators() {
  static const ConfigValidators v = [] {
    ConfigValidators out;
    out.sensor = [](const SensorConfig& s) -> std::string {
      Config one;
      one.sensors.push_back(s);
      try {
        (void)make_decoder(device_spec(one, 0));
      } catch (const std::exception& e) {
        return e.what();
      }
      return {};
    };
    out.sensor_warning = [](const SensorConfig& s) -> std::string {
      Config one;
      one.sensors.push_back(s);
      try {
        return serial_link_warning(device_spec(one, 0));
      } catch (const std::exception&) {
        return {};  // reported as an error by `sensor`
      }
    };
    return out;
  }();
  return v;
}

}  // namespace mocap::daemon
