// Small command-line parser shared by the programs: "--name value", "--name=value", flags and
// positionals, with clear errors for unknown options and missing values.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace mocap {

class CliArgs {
 public:
  /// Declares an option taking a value (e.g. "--rate") or a boolean flag.
  CliArgs& option(std::string name, std::string help);
  CliArgs& flag(std::string name, std::string help);
  /// Options that may be given several times ("--set a=1 --set b=2").
  CliArgs& multi(std::string name, std::string help);

  /// Parses argv[first..argc). Returns false and fills error() on bad input.
  bool parse(int argc, char** argv, int first = 1);

  bool has(std::string_view name) const;
  std::optional<std::string> get(std::string_view name) const;
  std::string get_or(std::string_view name, std::string fallback) const;
  /// Numeric accessors: fill error() and return false on a malformed number.
  bool get_double(std::string_view name, double& out) const;
  bool get_int(std::string_view name, long& out) const;
  std::vector<std::string> get_all(std::string_view name) const;
  const std::vector<std::string>& positional() const { return positional_; }
  const std::string& error() const { return error_; }
  /// "  --name VALUE  help" lines for usage messages.
  std::string help() const;

 private:
  struct Spec {
    std::string name, help;
    bool takes_value = true, repeat = false;
  };
  const Spec* find(std::string_view name) const;
  std::vector<Spec> specs_;
  std::vector<std::pair<std::string, std::string>> values_;
  std::vector<std::string> positional_;
  mutable std::string error_;
};

}  // namespace mocap
