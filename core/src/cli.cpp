// Command-line conventions shared by the programs (mocap/core/cli.hpp), on CLI11.
#include "mocap/core/cli.hpp"

#include <cctype>
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

/// The deepest subcommand being parsed (the app itself when none).
const CLI::App* deepest(const CLI::App& app) {
  const CLI::App* cur = &app;
  while (true) {
    const auto subs = cur->get_subcommands();
    if (subs.empty()) return cur;
    cur = subs.front();
  }
}

/// For a conflict or a missing companion option: each option the message names, with its
/// description (which says what it is for, and so why it does not go with the other).
std::string explain_options(const CLI::App& app, const std::string& message) {
  std::string out;
  std::size_t at = 0;
  while ((at = message.find("--", at)) != std::string::npos) {
    std::size_t end = at + 2;
    while (end < message.size() &&
           (std::isalnum(static_cast<unsigned char>(message[end])) || message[end] == '-'))
      ++end;
    const std::string name = message.substr(at, end - at);
    at = end;
    for (const CLI::App* a = deepest(app); a; a = a->get_parent()) {
      const CLI::Option* o = a->get_option_no_throw(name);
      if (!o) continue;
      if (out.find("  " + name + ":") == std::string::npos)
        out += "  " + name + ": " + o->get_description() + "\n";
      break;
    }
  }
  return out;
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

CLI::Option* deprecate_alias(CLI::App& app, CLI::Option* alias, CLI::Option* canonical) {
  const std::string name = alias->get_name(), instead = canonical->get_name();
  std::string who = app.get_name();  // "mocap replay"
  for (const CLI::App* p = app.get_parent(); p; p = p->get_parent())
    who = p->get_name() + " " + who;
  // Not CLI11's excludes(): it names a hidden option as "" (an empty "Excludes:" in the
  // canonical option's help, "--csv excludes " as the error). Option checks run after the whole
  // command line is read, so the canonical option's count is known here.
  alias->description("deprecated spelling of " + instead)
      ->group("")
      ->each([who, name, instead, canonical](const std::string&) {
        std::fprintf(stderr, "%s: warning: %s is deprecated; use %s\n", who.c_str(), name.c_str(),
                     instead.c_str());
        if (canonical->count() > 0) throw CLI::ExcludesError(name, instead);
      });
  alias->default_str("");
  return alias;
}

std::optional<int> parse(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --help-all, --version
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    const std::string who = command_path(app);
    const bool conflict = dynamic_cast<const CLI::ExcludesError*>(&e) != nullptr ||
                          dynamic_cast<const CLI::RequiresError*>(&e) != nullptr;
    std::fprintf(stderr, "%s: %s\n%sRun '%s --help' for the options.\n", who.c_str(), e.what(),
                 conflict ? explain_options(app, e.what()).c_str() : "", who.c_str());
    return 2;
  }
  return std::nullopt;
}

}  // namespace mocap::cli
