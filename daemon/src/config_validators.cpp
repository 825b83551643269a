// The loader's cross-module checks: a sensor's driver and options must be accepted by the
// drivers' make_decoder; filter keys must be FilterParams names with valid values.
#include <stdexcept>

#include "mocap/daemon/config.hpp"
#include "mocap/daemon/daemon.hpp"
#include "mocap/drivers/device.hpp"
#include "mocap/filter/filter_param_names.hpp"

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
    out.filter_param = [](const std::string& name, const std::string& value) -> std::string {
      FilterParams p;
      std::string err;
      return set_filter_param(p, name + "=" + value, err) ? std::string() : err;
    };
    // Names from the "name=value" lines the filter module describes itself with.
    const std::string text = describe_filter_params(FilterParams{});
    for (size_t i = 0; i < text.size();) {
      size_t nl = text.find('\n', i);
      if (nl == std::string::npos) nl = text.size();
      const std::string line = text.substr(i, nl - i);
      if (auto eq = line.find('='); eq != std::string::npos)
        out.filter_param_names.push_back(line.substr(0, eq));
      i = nl + 1;
    }
    return out;
  }();
  return v;
}

}  // namespace mocap::daemon
