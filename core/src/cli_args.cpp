// Command-line parsing for the mocap programs.
#include "mocap/core/cli_args.hpp"

#include <cerrno>
#include <cstdlib>

namespace mocap {

CliArgs& CliArgs::option(std::string name, std::string help) {
  specs_.push_back({std::move(name), std::move(help), true, false});
  return *this;
}
CliArgs& CliArgs::flag(std::string name, std::string help) {
  specs_.push_back({std::move(name), std::move(help), false, false});
  return *this;
}
CliArgs& CliArgs::multi(std::string name, std::string help) {
  specs_.push_back({std::move(name), std::move(help), true, true});
  return *this;
}

const CliArgs::Spec* CliArgs::find(std::string_view name) const {
  for (const auto& s : specs_)
    if (s.name == name) return &s;
  return nullptr;
}

bool CliArgs::parse(int argc, char** argv, int first) {
  bool only_positional = false;
  for (int i = first; i < argc; ++i) {
    std::string_view a = argv[i];
    if (only_positional || a.size() < 2 || a.substr(0, 2) != "--") {
      positional_.emplace_back(a);
      continue;
    }
    if (a == "--") {
      only_positional = true;
      continue;
    }
    std::string name(a.substr(2)), value;
    bool inline_value = false;
    if (auto eq = name.find('='); eq != std::string::npos) {
      value = name.substr(eq + 1);
      name.resize(eq);
      inline_value = true;
    }
    const Spec* s = find(name);
    if (!s) {
      error_ = "unknown option --" + name;
      return false;
    }
    if (!s->takes_value) {
      if (inline_value) {
        error_ = "option --" + name + " takes no value";
        return false;
      }
      values_.emplace_back(name, "1");
      continue;
    }
    if (!inline_value) {
      if (i + 1 >= argc) {
        error_ = "option --" + name + " needs a value";
        return false;
      }
      value = argv[++i];
    }
    if (!s->repeat && has(name)) {
      error_ = "option --" + name + " given twice";
      return false;
    }
    values_.emplace_back(name, value);
  }
  return true;
}

bool CliArgs::has(std::string_view name) const {
  for (const auto& [k, v] : values_)
    if (k == name) return true;
  return false;
}

std::optional<std::string> CliArgs::get(std::string_view name) const {
  for (const auto& [k, v] : values_)
    if (k == name) return v;
  return std::nullopt;
}

std::string CliArgs::get_or(std::string_view name, std::string fallback) const {
  auto v = get(name);
  return v ? *v : fallback;
}

bool CliArgs::get_double(std::string_view name, double& out) const {
  auto v = get(name);
  if (!v) return true;
  char* end = nullptr;
  errno = 0;
  double d = std::strtod(v->c_str(), &end);
  if (v->empty() || *end != '\0' || errno != 0) {
    error_ = "option --" + std::string(name) + ": '" + *v + "' is not a number";
    return false;
  }
  out = d;
  return true;
}

bool CliArgs::get_int(std::string_view name, long& out) const {
  auto v = get(name);
  if (!v) return true;
  char* end = nullptr;
  errno = 0;
  long d = std::strtol(v->c_str(), &end, 10);
  if (v->empty() || *end != '\0' || errno != 0) {
    error_ = "option --" + std::string(name) + ": '" + *v + "' is not an integer";
    return false;
  }
  out = d;
  return true;
}

std::vector<std::string> CliArgs::get_all(std::string_view name) const {
  std::vector<std::string> out;
  for (const auto& [k, v] : values_)
    if (k == name) out.push_back(v);
  return out;
}

std::string CliArgs::help() const {
  std::string out;
  for (const auto& s : specs_) {
    std::string left = "  --" + s.name + (s.takes_value ? " VALUE" : "");
    if (left.size() < 24) left.resize(24, ' ');
    out += left + " " + s.help + "\n";
  }
  return out;
}

}  // namespace mocap
