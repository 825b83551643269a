// Command-line conventions shared by the four programs, on CLI11: every program and subcommand
// has -h/--help and --version (exit 0), help shows defaults, a usage error names the program
// and the problem and exits 2.
#pragma once

#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <vector>

namespace mocap::cli {

/// "PROGRAM VERSION", e.g. "mocapd 0.1.0 (v0.1-123-gabcdef)".
std::string version_line(const std::string& program);

/// A program's top-level app: --version, defaults captured and shown in help, options of the
/// program usable after a subcommand (fallthrough).
void setup_program(CLI::App& app);

/// A subcommand of `parent` with the program's conventions (its own --version, -h/--help).
CLI::App* add_command(CLI::App& parent, const std::string& name, const std::string& description);

/// A repeatable option taking one value per occurrence ("--set a=1 --set b=2"), so a value
/// never swallows the positional arguments after it.
CLI::Option* add_multi(CLI::App& app, const std::string& name, std::vector<std::string>& values,
                       const std::string& description);

/// Makes `alias` a deprecated spelling of `canonical`: hidden from help (not named in
/// canonical's either), warns when used, a usage error ("ALIAS excludes CANONICAL") together
/// with `canonical`. Returns `alias`.
CLI::Option* deprecate_alias(CLI::App& app, CLI::Option* alias, CLI::Option* canonical);

/// A deprecated spelling of `canonical` storing into `value` (usually canonical's own variable).
template <typename T>
CLI::Option* add_deprecated_alias(CLI::App& app, const std::string& name, T& value,
                                  CLI::Option* canonical) {
  return deprecate_alias(app, app.add_option(name, value), canonical);
}

/// Parses argv. Returns nullopt when the program should run, or the exit code when it is done:
/// 0 after printing help or the version (stdout), 2 after a usage error (stderr: "PROGRAM
/// [COMMAND]: problem", then where the help is). Subcommand callbacks run inside.
std::optional<int> parse(CLI::App& app, int argc, char** argv);

}  // namespace mocap::cli
