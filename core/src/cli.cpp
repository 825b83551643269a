// Command-line conventions shared by the programs (mocap/core/cli.hpp), on CLI11.
#include "mocap/core/cli.hpp"

#include <cstdio>

#include "mocap/core/version.hpp"

namespace mocap::cli {
namespace {

/// The whole name of the command being parsed: "mocap bench latency".
std::string command_path(const CLI::App& app) {
  std::string name = app.get_name();
  const CLI::App* cur = &app;
  while (true) {
    const auto subs = cur->get_subcommands();
    if (subs.empty()) break;
    cur = subs.front();
    name += " " + cur->get_name();
  }
  return name;
}

/// The command's own name (last word of the path) for its version line.
std::string version_of(const CLI::App& app) {
  std::string name = app.get_name();
  for (const CLI::App* p = app.get_parent(); p; p = p->get_parent())
    name = p->get_name() + " " + name;
  return version_line(name);
}

}  // namespace

std::string version_line(const std::string& program) {
  return program + " " + kVersion;
}

void setup_program(CLI::App& app) {
  app.option_defaults()->always_capture_default();
  app.get_formatter()->column_width(34);
  app.fallthrough();
  app.set_version_flag("--version", version_of(app), "print the version and exit");
  app.set_help_flag("-h,--help", "print this help and exit");
}

CLI::App* add_command(CLI::App& parent, const std::string& name, const std::string& description) {
  CLI::App* c = parent.add_subcommand(name, description);
  c->set_version_flag("--version", version_of(*c), "print the version and exit");
  return c;
}

CLI::Option* add_multi(CLI::App& app, const std::string& name, std::vector<std::string>& values,
                       const std::string& description) {
  CLI::Option* o = app.add_option(name, values, description)->allow_extra_args(false);
  o->default_str("");
  return o;
}

CLI::Option* add_deprecated_alias(CLI::App& app, const std::string& name, std::string& value,
                                  CLI::Option* canonical) {
  const std::string instead = canonical->get_name();
  CLI::Option* o =
      app.add_option(name, value)->group("")->each([name, instead](const std::string&) {
        std::fprintf(stderr, "warning: %s is deprecated; use %s\n", name.c_str(), instead.c_str());
      });
  o->excludes(canonical);
  return o;
}

std::optional<int> parse(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --help-all, --version
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    const std::string who = command_path(app);
    std::fprintf(stderr, "%s: %s\nRun '%s --help' for the options.\n", who.c_str(), e.what(),
                 who.c_str());
    return 2;
  }
  return std::nullopt;
}

}  // namespace mocap::cli
