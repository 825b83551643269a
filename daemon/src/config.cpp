// Loads and validates the daemon's TOML configuration: typed, range-checked reads with
// file:line:column errors, unknown keys rejected with the nearest valid name, and --set
// overrides. Which keys exist, their types and ranges come from the key tables
// (config_keys.cpp); this file knows how to read each type, plus the hand-read parts (body
// files, sensor options, cross-key checks). config_write.cpp prints a configuration back.
#include "mocap/daemon/config.hpp"
#include "config_keys.hpp"
#include "mocap/core/runtime_dir.hpp"
#include "mocap/core/text_check.hpp"

#include <arpa/inet.h>
#include <unistd.h>

#include <toml++/toml.h>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>
#include <sstream>
#include <variant>

#include "mocap/core/segments.hpp"
#include "mocap/filter/filter_param_names.hpp"
#include "mocap/skeleton/config_tables.hpp"
#include "mocap/skeleton/pose_frame.hpp"

namespace mocap::daemon {

std::string cut_for_message(std::string_view s, size_t max) {
  if (s.size() <= max) return std::string(s);
  // The start and the end (where a message names what was expected), the middle left out.
  const size_t head = max / 2, tail = max / 4;
  return std::string(s.substr(0, head)) + "... (" + std::to_string(s.size() - head - tail) +
         " more bytes not shown) ..." + std::string(s.substr(s.size() - tail));
}

std::string ConfigError::to_string() const {
  std::string out = file.empty() ? std::string("<config>") : cut_for_message(file, 256);
  if (line > 0) out += ":" + std::to_string(line) + ":" + std::to_string(column);
  out += ": ";
  if (!key.empty()) out += cut_for_message(key, kMaxConfigMessageKey) + ": ";
  return out + cut_for_message(message, kMaxConfigMessage);
}

std::string ConfigErrors::to_string() const {
  std::string out;
  for (const auto& e : errors)
    out += e.to_string() + "\n";
  return out;
}

int edit_distance(std::string_view a, std::string_view b) {
  std::vector<int> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j)
    row[j] = static_cast<int>(j);
  for (size_t i = 1; i <= a.size(); ++i) {
    int diag = row[0];
    row[0] = static_cast<int>(i);
    for (size_t j = 1; j <= b.size(); ++j) {
      const int up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

std::string nearest_name(std::string_view word, const std::vector<std::string_view>& candidates) {
  std::string best;
  int best_d = 1 << 30;
  for (auto c : candidates) {
    const int d = edit_distance(word, c);
    if (d < best_d) {
      best_d = d;
      best = std::string(c);
    }
  }
  // Plausible only if fewer than half the letters differ (and at most 4 edits).
  const int limit = std::min<int>(4, std::max<int>(1, static_cast<int>(word.size()) / 2));
  return best_d <= limit ? best : std::string();
}

std::string_view to_string(DemoPath p) {
  return p == DemoPath::direct ? "direct" : "device";
}

std::string default_control_socket() {
  std::string error;
  const std::string dir = private_runtime_dir(&error);
  if (dir.empty()) throw std::runtime_error(error);
  return dir + "/mocapd.sock";
}

namespace {

/// Thrown by Ctx::add past kMaxConfigErrors (not a std::exception: nothing else catches it).
struct TooManyConfigErrors {};

struct Ctx {
  std::string source;  // file name for nodes without a source
  ConfigErrors& errors;
  const ConfigValidators* validators = nullptr;

  void add(const toml::node* n, const std::string& key, std::string msg) {
    if (errors.errors.size() >= kMaxConfigErrors) {
      ConfigError stop;
      stop.file = source;
      stop.message = "more than " + std::to_string(kMaxConfigErrors) +
                     " problems: stopped checking (fix these first)";
      errors.errors.push_back(std::move(stop));
      throw TooManyConfigErrors{};
    }
    ConfigError e;
    e.file = source;
    e.key = cut_for_message(key, kMaxConfigMessageKey);  // long keys and values: cut, not echoed
    e.message = cut_for_message(msg, kMaxConfigMessage);
    if (n) {
      const auto& src = n->source();
      if (src.path && !src.path->empty()) e.file = *src.path;
      if (e.file.rfind("--set", 0) != 0) {
        e.line = static_cast<int>(src.begin.line);
        e.column = static_cast<int>(src.begin.column);
      }
    }
    errors.errors.push_back(std::move(e));
  }
};

std::string join(const std::string& path, std::string_view key) {
  return path.empty() ? std::string(key) : path + "." + std::string(key);
}

std::string list_of(const std::vector<std::string_view>& names) {
  std::string out;
  for (auto n : names)
    out += (out.empty() ? "" : ", ") + std::string(n);
  return out;
}

/// Reads the keys of one table with types and ranges, remembering which keys are known.
class TableReader {
 public:
  TableReader(const toml::table* t, const toml::node* where, std::string path, Ctx& ctx)
      : t_(t), where_(where), path_(std::move(path)), ctx_(ctx) {}

  const toml::node* node(std::string_view key) {
    known_.emplace_back(key);
    return t_ ? t_->get(key) : nullptr;
  }

  void str(std::string_view key, std::string& out,
           const std::vector<std::string_view>& allowed = {}) {
    const toml::node* n = node(key);
    if (!n) return;
    auto v = n->value<std::string>();
    if (!n->is_string() || !v) return type_error(n, key, "a string");
    if (allowed.size() && std::find(allowed.begin(), allowed.end(), *v) == allowed.end()) {
      std::string msg = "'" + *v + "' is not one of " + list_of(allowed);
      auto near = nearest_name(*v, allowed);
      if (!near.empty()) msg += " (did you mean '" + near + "'?)";
      return ctx_.add(n, join(path_, key), msg);
    }
    out = *v;
  }

  void num(std::string_view key, double& out, double lo, double hi) {
    const toml::node* n = node(key);
    if (!n) return;
    if (!n->is_number()) return type_error(n, key, "a number");
    const double v = *n->value<double>();
    if (!std::isfinite(v) || v < lo || v > hi) {
      std::ostringstream m;
      m << v << " is out of range [" << lo << ", " << hi << "]";
      return ctx_.add(n, join(path_, key), m.str());
    }
    out = v;
  }

  /// Any number, infinities and NaN included (the filter's parameters, as they always were).
  void any_number(std::string_view key, double& out) {
    const toml::node* n = node(key);
    if (!n) return;
    if (!n->is_number()) return type_error(n, key, "a number");
    out = *n->value<double>();
  }

  template <typename Int>
  void integer(std::string_view key, Int& out, int64_t lo, int64_t hi) {
    const toml::node* n = node(key);
    if (!n) return;
    if (!n->is_integer()) return type_error(n, key, "an integer");
    const int64_t v = *n->value<int64_t>();
    if (v < lo || v > hi) {
      return ctx_.add(n, join(path_, key),
                      std::to_string(v) + " is out of range [" + std::to_string(lo) + ", " +
                          std::to_string(hi) + "]");
    }
    out = static_cast<Int>(v);
  }

  void boolean(std::string_view key, bool& out) {
    const toml::node* n = node(key);
    if (!n) return;
    if (!n->is_boolean()) return type_error(n, key, "true or false");
    out = *n->value<bool>();
  }

  /// An array of three finite numbers (reported and false otherwise).
  bool three_numbers(const toml::node* n, std::string_view key, std::array<double, 3>& v) {
    const toml::array* a = n->as_array();
    bool ok = a && a->size() == 3;
    for (size_t i = 0; ok && i < 3; ++i) {
      const auto x = (*a)[i].value<double>();
      ok = (*a)[i].is_number() && x && std::isfinite(*x);
      if (ok) v[i] = *x;
    }
    if (!ok) type_error(n, key, "an array of three numbers [x, y, z]");
    return ok;
  }

  /// A direction: an array of three finite numbers, not all zero.
  void direction(std::string_view key, std::optional<std::array<double, 3>>& out) {
    const toml::node* n = node(key);
    std::array<double, 3> v{};
    if (!n || !three_numbers(n, key, v)) return;
    if (std::hypot(v[0], v[1], v[2]) < 1e-6)
      return ctx_.add(n, join(path_, key), "is the zero vector (needs a direction)");
    out = v;
  }

  /// Three numbers, each within [lo, hi].
  void ranged_triple(std::string_view key, std::optional<std::array<double, 3>>& out, double lo,
                     double hi) {
    const toml::node* n = node(key);
    std::array<double, 3> v{};
    if (!n || !three_numbers(n, key, v)) return;
    for (double x : v) {
      if (x < lo || x > hi) {
        std::ostringstream m;
        m << x << " is out of range [" << lo << ", " << hi << "]";
        return ctx_.add(n, join(path_, key), m.str());
      }
    }
    out = v;
  }

  /// An array of lo..hi strings, each a segment name or "" (an unused slot).
  void segment_names(std::string_view key, std::vector<std::string>& out, std::size_t lo,
                     std::size_t hi) {
    const toml::node* n = node(key);
    if (!n) return;
    const toml::array* a = n->as_array();
    if (!a || a->size() < lo || a->size() > hi)
      return type_error(
          n, key,
          ("an array of " + std::to_string(lo) + " to " + std::to_string(hi) + " segment names")
              .c_str());
    std::vector<std::string> v;
    for (const toml::node& e : *a) {
      const auto s = e.value<std::string>();
      if (!e.is_string() || !s) return type_error(&e, key, "an array of segment names");
      if (!s->empty() && !segment_from_name(*s)) {
        std::string msg = "'" + *s + "' is not a segment name";
        auto near = nearest_name(
            *s, std::vector<std::string_view>(kSegmentNames.begin(), kSegmentNames.end()));
        if (!near.empty()) msg += " (did you mean '" + near + "'?)";
        return ctx_.add(&e, join(path_, key), msg);
      }
      v.push_back(*s);
    }
    out = std::move(v);
  }

  /// A sub-table (nullptr if absent or not a table; the latter is reported).
  const toml::table* table(std::string_view key) {
    const toml::node* n = node(key);
    if (!n) return nullptr;
    if (!n->is_table()) {
      type_error(n, key, "a table");
      return nullptr;
    }
    return n->as_table();
  }

  /// Reports keys that were never asked for, with the nearest known name.
  /// A key of a removed feature: accepted, ignored, and named in the warnings.
  void removed(std::string_view key, std::string_view why) {
    if (node(key))
      ctx_.errors.warnings.push_back(join(path_, key) + ": removed (" + std::string(why) +
                                     "); ignored");
  }

  void finish() {
    if (!t_) return;
    for (const auto& [k, v] : *t_) {
      if (std::find(known_.begin(), known_.end(), k.str()) != known_.end()) continue;
      std::string msg = "unknown key";
      auto near =
          nearest_name(k.str(), std::vector<std::string_view>(known_.begin(), known_.end()));
      if (!near.empty())
        msg += " (did you mean '" + near + "'?)";
      else if (known_.size() <= 16)
        msg += " (valid keys: " + list_known() + ")";
      else  // e.g. the filter's parameters: too many to list in one line
        msg += " (mocapd --print-config-reference lists the valid keys)";
      ctx_.add(&v, join(path_, k.str()), msg);
    }
  }

  const std::string& path() const { return path_; }
  const toml::node* where() const { return where_; }
  /// The key's node without marking it known (nullptr if absent).
  const toml::node* peek(std::string_view key) const { return t_ ? t_->get(key) : nullptr; }
  Ctx& ctx() { return ctx_; }

 private:
  void type_error(const toml::node* n, std::string_view key, const char* want) {
    ctx_.add(n, join(path_, key), std::string("expected ") + want);
  }
  std::string list_known() const {
    std::string out;
    for (const auto& k : known_)
      out += (out.empty() ? "" : ", ") + k;
    return out;
  }

  const toml::table* t_;
  const toml::node* where_;
  std::string path_;
  Ctx& ctx_;
  std::vector<std::string> known_;  // owned: some keys are built at run time
};

using keys::number_text;

/// A scalar's text: strings as they are, numbers (shortest exact text) and booleans as TOML
/// writes them.
bool scalar_text(const toml::node& v, std::string& out) {
  if (v.is_string())
    out = *v.value<std::string>();
  else if (v.is_integer())
    out = std::to_string(*v.value<int64_t>());
  else if (v.is_floating_point())
    out = number_text(*v.value<double>());
  else if (v.is_boolean())
    out = *v.value<bool>() ? "true" : "false";
  else
    return false;
  return true;
}

bool valid_ipv4(const std::string& s) {
  in_addr a{};
  return inet_pton(AF_INET, s.c_str(), &a) == 1;
}

/// Reads one key of section S into the member its accessor `at` returns, by the member's type.
template <class S, class T>
void read_value(TableReader& r, const keys::Key<S>& k, T& (*at)(S&), S& s) {
  T& v = at(s);
  if constexpr (std::is_same_v<T, bool>) {
    r.boolean(k.name, v);
  } else if constexpr (std::is_same_v<T, int>) {
    r.integer(k.name, v, static_cast<int64_t>(k.lo), static_cast<int64_t>(k.hi));
  } else if constexpr (std::is_same_v<T, uint64_t>) {
    r.integer(k.name, v, static_cast<int64_t>(k.lo),
              k.hi >= 9.2e18 ? INT64_MAX : static_cast<int64_t>(k.hi));
  } else if constexpr (std::is_same_v<T, double>) {
    r.num(k.name, v, k.lo, k.hi);
  } else if constexpr (std::is_same_v<T, std::string>) {
    if (k.choices.empty())
      r.str(k.name, v);
    else
      r.str(k.name, v, keys::split_choices(k.choices));
    if (k.ipv4 && !valid_ipv4(v))
      r.ctx().add(r.peek(k.name), join(r.path(), k.name), "'" + v + "' is not an IPv4 address");
  } else if constexpr (std::is_enum_v<T>) {
    std::string name;
    r.str(k.name, name, keys::split_choices(k.choices));
    if (!name.empty()) keys::enum_from_name(name, v);
  } else if constexpr (std::is_same_v<T, std::optional<std::array<double, 3>>>) {
    if (k.direction)
      r.direction(k.name, v);
    else
      r.ranged_triple(k.name, v, k.lo, k.hi);
  } else {
    static_assert(std::is_same_v<T, std::vector<std::string>>);
    r.segment_names(k.name, v, static_cast<std::size_t>(k.lo), static_cast<std::size_t>(k.hi));
  }
}

/// Reads the keys of section S that its table binds to members; warns about removed ones.
/// Hand-read keys (no member) are read by their section's code, which marks them known.
template <class S>
void read_keys(TableReader& r, const keys::Section<S>& sec, S& s) {
  for (const keys::Key<S>& k : sec.keys) {
    if (!k.removed.empty()) {
      r.removed(k.name, k.removed);
      continue;
    }
    std::visit(
        [&](auto at) {
          if constexpr (!std::is_same_v<decltype(at), std::monostate>) read_value(r, k, at, s);
        },
        k.at);
  }
}

bool valid_axis_remap(std::string_view s) {
  // Three comma-separated axes, each [+|-]x|y|z, a permutation of x, y, z.
  bool seen[3] = {false, false, false};
  int count = 0;
  size_t i = 0;
  while (i <= s.size()) {
    size_t j = s.find(',', i);
    if (j == std::string_view::npos) j = s.size();
    std::string_view a = s.substr(i, j - i);
    if (!a.empty() && (a[0] == '-' || a[0] == '+')) a.remove_prefix(1);
    if (a.size() != 1 || a[0] < 'x' || a[0] > 'z' || seen[a[0] - 'x']) return false;
    seen[a[0] - 'x'] = true;
    ++count;
    i = j + 1;
  }
  return count == 3;
}

// A sensor name: 1-23 bytes (the 24-byte NUL-padded field of pose records) of ASCII letters,
// digits, '_', '-' or non-ASCII UTF-8 characters ("Jos\u00e9"; the whole text was checked as
// UTF-8 before parsing, and 23 bytes never cut a character: longer names are refused). No
// spaces: control commands address a sensor by its name as one word.
bool valid_sensor_name(std::string_view s) {
  if (s.empty() || s.size() > 23) return false;
  if (text_problem(s)) return false;
  return std::all_of(s.begin(), s.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '-' || static_cast<unsigned char>(c) >= 0x80;
  });
}

void read_sensor(const toml::table& t, const toml::node* where, int index, Ctx& ctx,
                 SensorConfig& s) {
  const size_t errors_before = ctx.errors.errors.size();
  TableReader r(&t, where, "sensor[" + std::to_string(index) + "]", ctx);
  read_keys(r, keys::section<SensorConfig>(), s);
  if (const toml::table* opts = r.table("options")) {
    for (const auto& [k, v] : *opts) {
      std::string text;
      if (scalar_text(v, text))
        s.options[std::string(k.str())] = std::move(text);
      else
        ctx.add(&v, r.path() + ".options." + std::string(k.str()),
                "expected a string, number or boolean");
    }
  }
  r.finish();

  auto at = [&](std::string_view key) -> const toml::node* {
    const toml::node* n = t.get(key);
    return n ? n : where;
  };
  const std::string p = r.path();
  if (!valid_sensor_name(s.name))
    ctx.add(at("name"), p + ".name",
            "needs a name of 1-23 bytes: letters (UTF-8 too), digits, '_' or '-'");
  if (s.driver.empty()) ctx.add(at("driver"), p + ".driver", "needs a driver (protocol name)");
  const bool has_ids = s.vid >= 0 || s.pid >= 0;
  if (has_ids && (s.vid < 0 || s.pid < 0))
    ctx.add(at(s.vid < 0 ? "pid" : "vid"), p, "vid and pid go together");
  if (s.port.empty() && !has_ids) ctx.add(where, p, "needs either port or vid and pid");
  if (!s.port.empty() && has_ids)
    ctx.add(at("port"), p + ".port", "give either port or vid/pid, not both");
  if (!s.segment.empty() && !segment_from_name(s.segment)) {
    std::vector<std::string_view> names(kSegmentNames.begin(), kSegmentNames.end());
    std::string msg = "unknown segment '" + s.segment + "'";
    auto near = nearest_name(s.segment, names);
    if (!near.empty()) msg += " (did you mean '" + near + "'?)";
    ctx.add(at("segment"), p + ".segment", msg);
  }
  if (!valid_axis_remap(s.axis_remap))
    ctx.add(at("axis_remap"), p + ".axis_remap",
            "'" + s.axis_remap + "' is not a permutation like \"x,y,z\" or \"-y,x,z\"");
  if (ctx.errors.errors.size() == errors_before && ctx.validators && ctx.validators->sensor) {
    if (std::string err = ctx.validators->sensor(s); !err.empty())
      ctx.add(at("driver"), p + ".driver", err);
  }
  if (ctx.errors.errors.size() == errors_before && ctx.validators &&
      ctx.validators->sensor_warning) {
    if (std::string w = ctx.validators->sensor_warning(s); !w.empty())
      ctx.errors.warnings.push_back(p + " (" + s.name + "): " + w);
  }
}

/// [body]: the model file, then height_m and [body.segment.*]; the joint-limits file, then
/// [body.joint.*]. Errors inside the included files name their own file:line and the key that
/// included them.
void read_body(TableReader& b, BodyConfig& body, Ctx& ctx) {
  const auto add_table_error = [&ctx](const TomlPositionError& e, const std::string& key,
                                      const std::string& via) {
    ConfigError err;
    err.file = e.source;
    err.line = e.line;
    err.column = e.column;
    err.key = key;
    err.message = e.problem + via;
    ctx.errors.errors.push_back(std::move(err));
  };
  const auto source_of = [&ctx](const toml::node& n) {
    const auto& p = n.source().path;
    return p && !p->empty() ? std::string(*p) : ctx.source;
  };
  std::string model_file, limits_file;
  b.str("model", model_file);
  b.str("joint_limits", limits_file);
  const auto included = [&](const char* key) {
    const toml::node* n = b.node(key);
    return " (included by " + source_of(*n) + ":" + std::to_string(n->source().begin.line) +
           " body." + key + ")";
  };
  // An included file: its own errors at its own lines, naming the key that included it.
  const auto include = [&](const char* key, const std::string& file, auto load) {
    if (file.empty()) return;
    try {
      load(file);
    } catch (const TomlPositionError& e) {
      add_table_error(e, "", included(key));
    } catch (const std::exception& e) {
      ctx.add(b.node(key), std::string("body.") + key, e.what());
    }
  };
  include("model", model_file, [&](const std::string& f) { body.model = load_body_config(f); });
  include("joint_limits", limits_file,
          [&](const std::string& f) { body.limits = load_joint_limits(f); });
  if (const toml::node* n = b.node("segment")) {
    try {
      read_body_segments(*n, source_of(*n), body.model);
    } catch (const TomlPositionError& e) {
      add_table_error(e, "body.segment", "");
    }
  }
  if (const toml::node* n = b.node("joint")) {
    try {
      read_joint_limit_tables(*n, source_of(*n), body.limits);
    } catch (const TomlPositionError& e) {
      add_table_error(e, "body.joint", "");
    }
  }
}

/// What a section reads by hand besides its table's members: nothing, except [body] (the model
/// and joint-limits files, segment and joint tables) and [filter] (the FilterParams members).
template <class S>
void read_by_hand(TableReader&, S&, Ctx&) {}
void read_by_hand(TableReader& b, BodyConfig& body, Ctx& ctx) {
  read_body(b, body, ctx);
}
void read_by_hand(TableReader& f, FilterConfig& filter, Ctx&) {
  for (const FilterParamEntry& e : filter_param_table()) {
    if (e.is_flag())
      f.boolean(e.name, e.flag(filter.params));
    else
      f.any_number(e.name, e.number(filter.params));
  }
}

Config read_root(const toml::table& root, Ctx& ctx) {
  Config c;
  TableReader r(&root, &root, "", ctx);
  // A section "a.b" is read inside the reader of table "a" (which then reports a's unknown
  // keys); sections of one parent are consecutive in keys::for_each_section.
  std::unique_ptr<TableReader> parent;
  keys::for_each_section(c, [&](const auto& sec, auto& s) {
    const std::string path(sec.path);
    const size_t dot = path.find('.');
    const std::string head = dot == std::string::npos ? "" : path.substr(0, dot);
    if (parent && parent->path() != head) {
      parent->finish();
      parent.reset();
    }
    if (!head.empty() && !parent)
      parent = std::make_unique<TableReader>(r.table(head), &root, head, ctx);
    TableReader& up = parent ? *parent : r;
    const std::string leaf = head.empty() ? path : path.substr(dot + 1);
    TableReader t(up.table(leaf), &root, path, ctx);
    read_by_hand(t, s, ctx);
    read_keys(t, sec, s);
    t.finish();
  });
  if (parent) parent->finish();
  if (const toml::node* sn = r.node("sensor")) {
    const toml::array* arr = sn->as_array();
    if (!arr || !arr->is_array_of_tables()) {
      ctx.add(sn, "sensor", "expected [[sensor]] tables");
    } else {
      int i = 0;
      std::set<std::string> names, segments;
      for (const auto& el : *arr) {
        SensorConfig s;
        read_sensor(*el.as_table(), &el, i, ctx, s);
        const std::string p = "sensor[" + std::to_string(i) + "]";
        if (!s.name.empty() && !names.insert(s.name).second)
          ctx.add(el.as_table()->get("name"), p + ".name",
                  "duplicate sensor name '" + s.name + "'");
        if (!s.segment.empty() && !segments.insert(s.segment).second)
          ctx.add(el.as_table()->get("segment"), p + ".segment",
                  "segment '" + s.segment + "' already has a sensor");
        c.sensors.push_back(std::move(s));
        ++i;
      }
      if (c.sensors.size() > static_cast<size_t>(kMaxSensors))
        ctx.add(sn, "sensor", "at most " + std::to_string(kMaxSensors) + " sensors");
    }
  }
  r.finish();
  return c;
}

std::string toml_quote(std::string_view s) {
  std::string out = "\"";
  for (char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += ch;
    } else if (c < 0x20 || c == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += ch;
    }
  }
  return out + "\"";
}

bool is_index(std::string_view s) {
  return !s.empty() && s.size() < 4 && std::all_of(s.begin(), s.end(), ::isdigit);
}

/// Applies "a.b.c=VALUE" to the parsed document. Sensor entries are addressed by index or name:
/// "sensor.0.port=..." or "sensor.pelvis.port=...".
void apply_override(toml::table& root, const std::string& kv, Ctx& ctx) {
  const size_t eq = kv.find('=');
  if (eq == std::string::npos || eq == 0) {
    ctx.add(nullptr, kv, "--set needs KEY=VALUE");
    return;
  }
  const std::string key = kv.substr(0, eq), value = kv.substr(eq + 1);
  std::vector<std::string> parts;
  for (size_t i = 0;;) {
    size_t j = key.find('.', i);
    parts.push_back(key.substr(i, j == std::string::npos ? std::string::npos : j - i));
    if (j == std::string::npos) break;
    i = j + 1;
  }
  for (const auto& p : parts)
    if (p.empty()) return ctx.add(nullptr, key, "--set: empty key component");
  // Parse VALUE as TOML; a bare word becomes a string.
  toml::table parsed;
  const std::string src = "--set " + key;
  if (const auto bad = text_problem(value))
    return ctx.add(nullptr, key, "--set: bad value: " + bad->what);
  // VALUE as TOML if it is (non-ASCII only in its strings: toml_text_problem), else quoted.
  std::string ascii;  // what toml++ reads: non-ASCII only as escapes (text_check.hpp)
  bool as_is = !toml_text_problem("v = " + value, &ascii);
  if (as_is) {
    try {
      parsed = toml::parse(ascii, src);
    } catch (const toml::parse_error&) {
      as_is = false;
    }
  }
  if (!as_is) {
    try {
      if (toml_text_problem("v = " + toml_quote(value), &ascii))
        return ctx.add(nullptr, key, "--set: bad value");
      parsed = toml::parse(ascii, src);
    } catch (const toml::parse_error& e) {
      return ctx.add(nullptr, key,
                     std::string("--set: bad value: ") + std::string(e.description()));
    }
  }
  toml::table* t = &root;
  for (size_t i = 0; i + 1 < parts.size(); ++i) {
    toml::node* n = t->get(parts[i]);
    if (!n) {
      t->insert_or_assign(parts[i], toml::table{});
      n = t->get(parts[i]);
    }
    if (auto* arr = n->as_array()) {
      // Pick an element of an array of tables by index or by its "name".
      if (i + 2 >= parts.size())
        return ctx.add(nullptr, key, "--set: '" + parts[i] + "' needs an index or name");
      const std::string& sel = parts[++i];
      toml::table* found = nullptr;
      if (is_index(sel)) {
        const size_t idx = std::stoul(sel);
        if (idx < arr->size()) found = (*arr)[idx].as_table();
      } else {
        for (auto& el : *arr)
          if (auto* et = el.as_table(); et && et->get_as<std::string>("name") &&
                                        et->get_as<std::string>("name")->get() == sel)
            found = et;
      }
      if (!found) return ctx.add(nullptr, key, "--set: no " + parts[i - 1] + " '" + sel + "'");
      t = found;
      continue;
    }
    t = n->as_table();
    if (!t) return ctx.add(nullptr, key, "--set: '" + parts[i] + "' is not a table");
  }
  t->insert_or_assign(parts.back(), std::move(*parsed.get("v")));
}

}  // namespace

std::optional<Config> parse_config(std::string_view toml_text, std::string_view source_name,
                                   const std::vector<std::string>& overrides, ConfigErrors& errors,
                                   const ConfigValidators* validators) {
  Ctx ctx{std::string(source_name), errors, validators};
  toml::table root;
  if (toml_text.size() > kMaxConfigBytes) {
    errors.errors.push_back({std::string(source_name), 0, 0, "",
                             "configuration is " + std::to_string(toml_text.size()) +
                                 " bytes, over the 1 MiB limit; not read"});
    return std::nullopt;
  }
  std::string ascii;  // what toml++ reads: non-ASCII only as escapes (text_check.hpp)
  if (const auto bad = toml_text_problem(toml_text, &ascii)) {
    ConfigError err;
    err.file = std::string(source_name);
    err.line = static_cast<int>(bad->line);
    err.column = static_cast<int>(bad->column);
    err.message = bad->what;
    errors.errors.push_back(std::move(err));
    return std::nullopt;
  }
  try {
    root = toml::parse(ascii, source_name);
  } catch (const toml::parse_error& e) {
    ConfigError err;
    err.file = std::string(source_name);
    err.line = static_cast<int>(e.source().begin.line);
    err.column = static_cast<int>(e.source().begin.column);
    err.message = std::string(e.description());
    errors.errors.push_back(std::move(err));
    return std::nullopt;
  }
  try {
    for (const auto& kv : overrides)
      apply_override(root, kv, ctx);
    if (!errors.errors.empty()) return std::nullopt;
    Config c = read_root(root, ctx);
    c.source = std::string(source_name);
    if (!errors.errors.empty()) return std::nullopt;
    return c;
  } catch (const TooManyConfigErrors&) {
    return std::nullopt;
  }
}

std::optional<Config> load_config(const std::string& path,
                                  const std::vector<std::string>& overrides, ConfigErrors& errors,
                                  const ConfigValidators* validators) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    errors.errors.push_back({path, 0, 0, "", "is a directory, not a configuration file"});
    return std::nullopt;
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    errors.errors.push_back({path, 0, 0, "", "cannot open the file"});
    return std::nullopt;
  }
  // Read at most one byte past the limit: a huge file is refused without reading it all.
  std::string text(kMaxConfigBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<size_t>(in.gcount()));
  if (text.size() > kMaxConfigBytes) {
    errors.errors.push_back(
        {path, 0, 0, "", "larger than 1 MiB, the limit for a configuration file; not read"});
    return std::nullopt;
  }
  return parse_config(text, path, overrides, errors, validators);
}

std::optional<Config> with_overrides(const Config& c, const std::vector<std::string>& sets,
                                     std::string_view source_name, ConfigErrors& errors) {
  if (sets.empty()) return c;
  return parse_config(config_to_toml(c), source_name, sets, errors);
}

}  // namespace mocap::daemon
