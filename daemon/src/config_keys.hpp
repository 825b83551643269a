// The configuration's keys, each declared once: one table per section (name, type through the
// member it is bound to, range, unit, help) in config_keys.cpp. The tables drive the loader's
// typed reads and range checks, --print-config, the key list of `mocapd --help` and the key
// reference of docs/configuration.md (`mocapd --print-config-reference`). Private to the
// daemon library (config.cpp and config_keys.cpp).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "mocap/daemon/config.hpp"

namespace mocap::daemon::keys {

/// Where a key's value lives in its section struct S: an accessor returning the member (the
/// member's type is the key's type). std::monostate: a key read by hand-written code (body
/// files, sensor options) or a removed key; it is listed so that the docs and --help name it.
template <class S>
using Access =
    std::variant<std::monostate, bool& (*)(S&), int& (*)(S&), uint64_t& (*)(S&), double& (*)(S&),
                 std::string& (*)(S&), LogLevel& (*)(S&), CalibrationPose& (*)(S&),
                 HeadingSource& (*)(S&), DemoPath& (*)(S&),
                 std::optional<std::array<double, 3>>& (*)(S&), std::vector<std::string>& (*)(S&)>;

/// One key of section S.
template <class S>
struct Key {
  std::string_view name;
  Access<S> at;
  /// Range of a number or integer, of each element of a triple, or of a list's length.
  double lo = 0, hi = 0;
  std::string_view unit;  ///< "" when it has none
  /// Names allowed for an enum ("a, b, c"); the first of a parse is what to_string gives.
  std::string_view choices;
  /// Printed by --print-config only when it differs from the default (keys whose default means
  /// "absent", e.g. a sensor's port or vid).
  bool omit_default = false;
  /// A triple that is a direction (not all zero) rather than ranged numbers.
  bool direction = false;
  /// A string that must be an IPv4 address.
  bool ipv4 = false;
  /// Non-empty: the key of a removed feature, accepted with a warning giving this reason.
  std::string_view removed;
  /// Type and default shown in the docs for a hand-read key (other keys show the member's type
  /// and the struct's default).
  std::string_view doc_type, doc_default;
  std::string_view help;
};

/// A section: its dotted TOML path, a note for the docs, and its keys.
template <class S>
struct Section {
  std::string_view path;
  std::string_view note;
  std::span<const Key<S>> keys;
};

/// The table of section struct S (config_keys.cpp).
template <class S>
const Section<S>& section();
template <>
const Section<DaemonSection>& section();
template <>
const Section<PipelineConfig>& section();
template <>
const Section<FilterConfig>& section();
template <>
const Section<BodyConfig>& section();
template <>
const Section<CalibrationConfig>& section();
template <>
const Section<JsonOutputConfig>& section();
template <>
const Section<VmcOutputConfig>& section();
template <>
const Section<VrchatOutputConfig>& section();
template <>
const Section<PostureOutputConfig>& section();
template <>
const Section<RecordingConfig>& section();
template <>
const Section<DemoConfig>& section();
template <>
const Section<SensorConfig>& section();

/// Calls f(section<S>(), member) for every [section] of Config, in file order ([[sensor]] and
/// [filter]'s FilterParams are handled apart: see config.cpp).
template <class C, class F>
void for_each_section(C& c, F&& f) {
  f(section<DaemonSection>(), c.daemon);
  f(section<PipelineConfig>(), c.pipeline);
  f(section<FilterConfig>(), c.filter);
  f(section<BodyConfig>(), c.body);
  f(section<CalibrationConfig>(), c.calibration);
  f(section<JsonOutputConfig>(), c.outputs.json);
  f(section<VmcOutputConfig>(), c.outputs.vmc);
  f(section<VrchatOutputConfig>(), c.outputs.vrchat);
  f(section<PostureOutputConfig>(), c.outputs.posture);
  f(section<RecordingConfig>(), c.recording);
  f(section<DemoConfig>(), c.demo);
}

/// Parses an enum value from its name (to_string of each value); false if none matches.
template <class E>
bool enum_from_name(std::string_view name, E& out) {
  for (int i = 0; i < 16; ++i) {
    if (to_string(static_cast<E>(i)) == name) {
      out = static_cast<E>(i);
      return true;
    }
  }
  return false;
}

/// "a, b, c" split at commas and spaces.
std::vector<std::string_view> split_choices(std::string_view choices);
/// The shortest text that reads back as exactly `v`.
std::string number_text(double v);

}  // namespace mocap::daemon::keys
