// Writes a configuration back as TOML (--print-config, the configuration a recording stores):
// every key of the key tables (config_keys.cpp) by its type, numbers in their shortest exact
// form, plus the hand-written parts (body offsets and joint limits inline, sensor options, the
// filter parameters that differ from the defaults). parse_config reads the text back to the
// same configuration.
#include <toml++/toml.h>

#include <cstring>
#include <sstream>
#include <variant>

#include "config_keys.hpp"
#include "mocap/core/segments.hpp"
#include "mocap/daemon/config.hpp"
#include "mocap/filter/filter_param_names.hpp"
#include "mocap/skeleton/config_tables.hpp"

namespace mocap::daemon {

namespace {
// Strings as basic "..." strings only: toml++ 3.3 writes a string holding ''' and a newline as a
// multi-line literal string that does not parse back.
constexpr toml::format_flags kFormat = toml::toml_formatter::default_flags &
                                       ~toml::format_flags::allow_literal_strings &
                                       ~toml::format_flags::allow_multi_line_strings;
}  // namespace

namespace {

toml::array toml_vec3(const Eigen::Vector3d& v) {
  return toml::array{v.x(), v.y(), v.z()};
}

/// [body]'s segment and joint tables with every override inlined (no file keys), so a recorded
/// configuration is complete.
void write_by_hand(toml::table& t, const BodyConfig& b) {
  toml::table segments;
  for (int i = 0; i < kSegmentCount; ++i) {
    toml::table st;
    if (b.model.joint_offset_m[i])
      st.insert("joint_offset_m", toml_vec3(*b.model.joint_offset_m[i]));
    if (b.model.end_offset_m[i]) st.insert("end_offset_m", toml_vec3(*b.model.end_offset_m[i]));
    if (!st.empty()) segments.insert(std::string(kSegmentNames[i]), std::move(st));
  }
  if (!segments.empty()) t.insert("segment", std::move(segments));
  const JointLimits defaults = default_joint_limits();
  toml::table joints;
  for (int i = 1; i < kSegmentCount; ++i) {
    const JointLimit& l = b.limits.joint[i];
    if (l == defaults.joint[i]) continue;
    joints.insert(std::string(kJointNames[i]),
                  toml::table{{"limited", l.limited},
                              {"hinge", l.hinge},
                              {"a_deg", toml::array{l.a_min_deg, l.a_max_deg}},
                              {"b_deg", toml::array{l.b_min_deg, l.b_max_deg}},
                              {"twist_deg", toml::array{l.twist_min_deg, l.twist_max_deg}}});
  }
  if (!joints.empty()) t.insert("joint", std::move(joints));
}

/// [filter]'s FilterParams members that differ from the filter's defaults (a recording then
/// names only what was tuned, and still loads when a parameter is later removed).
void write_by_hand(toml::table& t, const FilterConfig& f) {
  static const FilterParams defaults;
  for (const FilterParamEntry& e : filter_param_table()) {
    if (e.is_flag()) {
      if (e.flag(f.params) != e.flag(defaults)) t.insert(e.name, e.flag(f.params));
    } else {
      const double v = e.number(f.params), v0 = e.number(defaults);
      if (std::memcmp(&v, &v0, sizeof v) != 0) t.insert(e.name, v);
    }
  }
}

void write_by_hand(toml::table& t, const SensorConfig& s) {
  toml::table opts;
  for (const auto& [k, v] : s.options)
    opts.insert(k, v);
  t.insert("options", std::move(opts));
}

template <class S>
void write_by_hand(toml::table&, const S&) {}

/// Writes the table-bound keys of section S (and its hand-written parts) into `t`.
template <class S>
void write_keys(toml::table& t, const keys::Section<S>& sec, const S& s) {
  static const S defaults{};
  S& cs = const_cast<S&>(s);  // the accessors only read here
  S& cd = const_cast<S&>(defaults);
  for (const keys::Key<S>& k : sec.keys) {
    std::visit(
        [&](auto at) {
          if constexpr (!std::is_same_v<decltype(at), std::monostate>) {
            const auto& v = at(cs);
            using T = std::decay_t<decltype(v)>;
            if (k.omit_default && v == at(cd)) return;
            const std::string name(k.name);
            if constexpr (std::is_same_v<T, uint64_t>)
              t.insert(name, static_cast<int64_t>(v));
            else if constexpr (std::is_enum_v<T>)
              t.insert(name, std::string(to_string(v)));
            else if constexpr (std::is_same_v<T, std::optional<std::array<double, 3>>>) {
              if (v) t.insert(name, toml::array{(*v)[0], (*v)[1], (*v)[2]});
            } else if constexpr (std::is_same_v<T, std::vector<std::string>>) {
              toml::array a;
              for (const auto& x : v)
                a.push_back(x);
              t.insert(name, std::move(a));
            } else {
              t.insert(name, v);
            }
          }
        },
        k.at);
  }
  write_by_hand(t, s);
}

/// The table at dotted `path` under `root`, created if absent.
toml::table& table_at(toml::table& root, std::string_view path) {
  toml::table* t = &root;
  while (!path.empty()) {
    const size_t dot = path.find('.');
    const std::string part(path.substr(0, dot));
    if (!t->get(part)) t->insert(part, toml::table{});
    t = t->get_as<toml::table>(part);
    path = dot == std::string_view::npos ? std::string_view() : path.substr(dot + 1);
  }
  return *t;
}

}  // namespace

std::string config_to_toml(const Config& c) {
  toml::table root;
  keys::for_each_section(
      c, [&](const auto& sec, const auto& s) { write_keys(table_at(root, sec.path), sec, s); });
  toml::array sensors;
  for (const auto& s : c.sensors) {
    toml::table t;
    write_keys(t, keys::section<SensorConfig>(), s);
    sensors.push_back(std::move(t));
  }
  if (!sensors.empty()) root.insert("sensor", std::move(sensors));
  std::ostringstream out;
  out << "# mocapd effective configuration" << (c.source.empty() ? "" : " (from " + c.source + ")")
      << "\n"
      << toml::toml_formatter(root, kFormat) << "\n";
  return out.str();
}

}  // namespace mocap::daemon
