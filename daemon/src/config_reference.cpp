// The configuration keys described for people, from the key tables (config_keys.cpp): the
// markdown key reference of docs/configuration.md (`mocapd --print-config-reference`) and the
// key list of `mocapd --help`.
#include <charconv>
#include <cmath>
#include <type_traits>

#include "config_keys.hpp"
#include "mocap/filter/filter_param_names.hpp"

namespace mocap::daemon {
namespace {

using keys::number_text;

/// A range bound: whole numbers in full ("4000000", not "4e+06").
std::string bound_text(double v) {
  if (v >= 9.2e18) return "2^63-1";
  if (v == std::floor(v) && std::fabs(v) < 1e15) return std::to_string(static_cast<int64_t>(v));
  return number_text(v);
}

std::string range_text(double lo, double hi) {
  return bound_text(lo) + ".." + bound_text(hi);
}

/// One markdown row: key, type (unit), default, range, meaning.
struct Row {
  std::string key, type, def, range, help;
};

template <class S, class T>
Row row_of(const keys::Key<S>& k, T& (*at)(S&)) {
  static S defaults{};
  const T& v = at(defaults);
  Row r;
  if constexpr (std::is_same_v<T, bool>) {
    r.type = "boolean";
    r.def = v ? "true" : "false";
  } else if constexpr (std::is_same_v<T, int> || std::is_same_v<T, uint64_t>) {
    r.type = "integer";
    r.def = std::to_string(v);
    r.range = range_text(k.lo, k.hi);
  } else if constexpr (std::is_same_v<T, double>) {
    r.type = "number";
    r.def = number_text(v);
    r.range = range_text(k.lo, k.hi);
  } else if constexpr (std::is_same_v<T, std::string>) {
    r.type = k.ipv4 ? "IPv4 address" : "string";
    r.def = "\"" + v + "\"";
  } else if constexpr (std::is_enum_v<T>) {
    r.type = "one of " + std::string(k.choices);
    r.def = "\"" + std::string(to_string(v)) + "\"";
  } else if constexpr (std::is_same_v<T, std::optional<std::array<double, 3>>>) {
    r.type = k.direction ? "direction [x, y, z]" : "[x, y, z]";
    if (!k.direction) r.range = range_text(k.lo, k.hi) + " each";
  } else {
    r.type = "segment names";
    r.range = range_text(k.lo, k.hi) + " names";
    for (const auto& s : v)
      r.def += (r.def.empty() ? "" : ", ") + ("\"" + s + "\"");
    r.def = "[" + r.def + "]";
  }
  return r;
}

std::string code(const std::string& s) {
  return s.empty() ? std::string() : "`" + s + "`";
}

template <class S>
std::string section_markdown(const keys::Section<S>& sec) {
  const bool array = std::is_same_v<S, SensorConfig>;
  std::string out = "### `" + std::string(array ? "[[" : "[") + std::string(sec.path) +
                    (array ? "]]" : "]") + "`\n";
  if (!sec.note.empty()) out += std::string(sec.note) + "\n\n";
  out += "| key | type | default | range | meaning |\n|---|---|---|---|---|\n";
  std::string removed;
  const auto add = [&out](const Row& r, bool words = false) {
    out += "| `" + r.key + "` | " + r.type + " | " + (words ? r.def : code(r.def)) + " | " +
           r.range + " | " + r.help + " |\n";
  };
  for (const keys::Key<S>& k : sec.keys) {
    if (!k.removed.empty()) {
      removed += std::string(removed.empty() ? "" : "; ") + "`" + std::string(k.name) + "` (" +
                 std::string(k.removed) + ")";
      continue;
    }
    Row r = std::visit(
        [&](auto at) {
          if constexpr (std::is_same_v<decltype(at), std::monostate>)
            return Row{};
          else
            return row_of(k, at);
        },
        k.at);
    r.key = std::string(k.name);
    if (!k.unit.empty()) r.type += " (" + std::string(k.unit) + ")";
    if (!k.doc_type.empty()) r.type = std::string(k.doc_type);
    if (!k.doc_default.empty()) r.def = std::string(k.doc_default);  // words, not a value
    r.help = std::string(k.help);
    add(r, !k.doc_default.empty());
  }
  if constexpr (std::is_same_v<S, FilterConfig>) {
    static const FilterParams defaults;
    for (const FilterParamEntry& e : filter_param_table()) {
      Row r;
      r.key = e.name;
      if (e.is_flag()) {
        r.type = "boolean";
        r.def = e.flag(defaults) ? "true" : "false";
      } else {
        r.type = "number";
        r.def = number_text(e.number(defaults));
      }
      r.help = "`FilterParams::" + std::string(e.member) + "`";
      add(r);
    }
  }
  if (!removed.empty())
    out += "\nRemoved keys, accepted and ignored with a warning: " + removed + ".\n";
  return out + "\n";
}

}  // namespace

std::string config_reference_markdown() {
  std::string out;
  Config c;
  keys::for_each_section(c, [&](const auto& sec, auto&) { out += section_markdown(sec); });
  out += section_markdown(keys::section<SensorConfig>());
  out.pop_back();  // one newline at the end
  return out;
}

std::string config_key_summary() {
  std::string out;
  const auto line = [&out](std::string_view path, const auto& sec) {
    out += "  " + std::string(path) + ":";
    for (const auto& k : sec.keys)
      if (k.removed.empty()) out += " " + std::string(k.name);
    if (path == "filter") out += " (and the FilterParams names)";
    out += "\n";
  };
  Config c;
  keys::for_each_section(c, [&](const auto& sec, auto&) { line(sec.path, sec); });
  line("sensor.NAME", keys::section<SensorConfig>());
  return out;
}

}  // namespace mocap::daemon
