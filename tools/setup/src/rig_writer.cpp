// The rig file `mocap setup` writes (see rig_writer.hpp).
#include "mocap/setup/rig_writer.hpp"

#include <cstdio>
#include <sstream>

namespace mocap::setup {
namespace {

/// A TOML basic string.
std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char b[8];
      std::snprintf(b, sizeof b, "\\u%04x", static_cast<unsigned>(c));
      out += b;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string hex(int v) {
  char b[8];
  std::snprintf(b, sizeof b, "0x%04x", v);
  return b;
}

/// An option's value: numbers stay numbers (tracker = 0), the rest are strings.
std::string option_value(const std::string& v) {
  const bool number = !v.empty() && v.find_first_not_of("0123456789") == std::string::npos;
  return number ? v : quoted(v);
}

}  // namespace

std::string rig_toml(const RigPlan& plan) {
  std::ostringstream t;
  t << "# Rig written by `mocap setup`: each sensor was assigned to the segment that moved it.\n"
       "# Check it with `mocapd --check-config FILE`, run it with `mocapd --config FILE`.\n";
  for (const auto& s : plan.left_out)
    t << "# heard but never moved alone, left out: " << s << "\n";
  for (const auto& s : plan.silent)
    t << "# found but sent nothing: " << s << "\n";
  for (const auto& s : plan.no_sensor)
    t << "# no sensor moved for segment " << s << "\n";
  t << "\n[pipeline]\nrate_hz = 120\n";
  if (!plan.use_mag) t << "\n[filter]\nuse_mag = false\n";
  t << "\n[calibration]\npose = \"npose\"\ncountdown_s = 3.0\n";
  if (!plan.calibration_file.empty()) t << "file = " << quoted(plan.calibration_file) << "\n";
  for (const auto& s : plan.sensors) {
    t << "\n[[sensor]]\nname = " << quoted(s.name) << "\ndriver = " << quoted(s.driver) << "\n";
    if (s.baud > 0) t << "baud = " << s.baud << "\n";
    if (!s.port.empty()) {
      t << "port = " << quoted(s.port) << "\n";
    } else {
      t << "vid = " << hex(s.vid) << "\npid = " << hex(s.pid) << "\n";
      if (!s.serial.empty()) t << "serial = " << quoted(s.serial) << "\n";
      if (s.hid) t << "hid = true\n";
    }
    if (s.rate_hz > 0) t << "rate_hz = " << s.rate_hz << "\n";
    t << "segment = " << quoted(s.segment) << "\n";
    if (!s.options.empty()) {
      t << "options = {";
      bool first = true;
      for (const auto& [k, v] : s.options) {
        t << (first ? " " : ", ") << k << " = " << option_value(v);
        first = false;
      }
      t << " }\n";
    }
  }
  return t.str();
}

}  // namespace mocap::setup
