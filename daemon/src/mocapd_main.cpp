// mocapd: the motion-capture daemon. Parses the command line, loads and validates the
// configuration, assembles the daemon (daemon_setup.hpp) and runs until SIGINT/SIGTERM or
// `mocapctl quit`; or replays a recorded session through the same pipeline.
#include <signal.h>
#include <sys/signalfd.h>
#include <unistd.h>

#include <cstdio>
#include <memory>
#include <string>

#include "mocap/core/cli.hpp"
#include "mocap/daemon/config.hpp"
#include "mocap/daemon/daemon.hpp"
#include "mocap/daemon/daemon_setup.hpp"
#include "mocap/daemon/instance_lock.hpp"

using namespace mocap;
using namespace mocap::daemon;

namespace {

/// mocapd's command line: every option declared in declare_options().
struct Options {
  std::string config, check_config, replay;
  std::vector<std::string> sets;
  bool print_config = false, print_config_reference = false, demo = false;
  double speed = 1.0;
  std::string log_level;
};

void declare_options(CLI::App& app, Options& o) {
  app.footer(
      "Forms:\n"
      "  mocapd [--config FILE | --demo] [--set KEY=VALUE ...] [options]\n"
      "  mocapd --check-config FILE [--set KEY=VALUE ...]\n"
      "  mocapd --print-config [--config FILE] [--set KEY=VALUE ...]\n"
      "  mocapd --replay SESSION [--speed 0|1|X] [--config FILE]\n\n"
      "Configuration keys (--set SECTION.KEY=VALUE; --print-config-reference describes each):\n" +
      config_key_summary());
  CLI::Option* config = app.add_option("--config", o.config, "rig configuration (TOML)");
  CLI::Option* check =
      app.add_option("--check-config", o.check_config,
                     "validate a configuration file and exit (runs nothing: not with --config, "
                     "--demo, --replay or --print-config)");
  CLI::Option* print =
      app.add_flag("--print-config", o.print_config,
                   "print the effective configuration (defaults included) and exit");
  app.add_flag("--print-config-reference", o.print_config_reference,
               "print the configuration keys' reference (markdown, as in docs/configuration.md) "
               "and exit");
  cli::add_multi(app, "--set", o.sets,
                 "override a configuration key, e.g. --set outputs.json.port=7400");
  CLI::Option* demo = app.add_flag(
      "--demo", o.demo,
      "run the virtual performer's simulated sensors (config/demo.toml rig; live, so not "
      "with --replay)");
  CLI::Option* replay =
      app.add_option("--replay", o.replay,
                     "play a recorded session through the pipeline instead of live sensors, "
                     "and exit");
  app.add_option("--speed", o.speed,
                 "replay speed (of --replay): 1 = real time, 0 = as fast as possible, X = factor")
      ->check(CLI::NonNegativeNumber)
      ->needs(replay);
  app.add_option("--log-level", o.log_level, "daemon log level (overrides daemon.log_level)");
  // --check-config checks one file and runs nothing: every other mode conflicts with it.
  check->excludes(config)->excludes(print)->excludes(demo)->excludes(replay);
  demo->excludes(replay);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"mocapd: the motion-capture daemon", "mocapd"};
  cli::setup_program(app);
  Options o;
  declare_options(app, o);
  if (auto done = cli::parse(app, argc, argv)) return *done;
  if (o.print_config_reference) {
    std::printf("%s", config_reference_markdown().c_str());
    return 0;
  }
  std::vector<std::string> sets = o.sets;
  if (!o.log_level.empty()) sets.push_back("daemon.log_level=" + o.log_level);

  // Configuration: --check-config FILE, --config FILE, or the demo rig.
  const bool check = !o.check_config.empty();
  const std::string config_path = check ? o.check_config : o.config;
  ConfigErrors errors;
  std::optional<Config> cfg;
  if (!config_path.empty())
    cfg = load_config(config_path, sets, errors, &default_validators());
  else
    cfg = parse_config("", "<defaults>", sets, errors, &default_validators());
  for (const std::string& w : errors.warnings)
    std::fprintf(stderr, "mocapd: warning: %s\n", w.c_str());
  if (!cfg) {
    std::fprintf(stderr, "%s", errors.to_string().c_str());
    std::fprintf(stderr, "mocapd: configuration invalid (%zu problem%s); not starting\n",
                 errors.errors.size(), errors.errors.size() == 1 ? "" : "s");
    return 1;
  }
  if (!check && !o.demo && o.replay.empty() && !o.print_config && cfg->sensors.empty()) {
    std::fprintf(stderr,
                 "mocapd: no sensors configured: give --config RIG.toml (see config/) or --demo\n");
    return 2;
  }
  if (check) {
    std::printf("%s: OK (%zu sensor%s)\n", config_path.c_str(), cfg->sensors.size(),
                cfg->sensors.size() == 1 ? "" : "s");
    return 0;
  }
  if (o.print_config) {
    std::fputs(config_to_toml(*cfg).c_str(), stdout);
    return 0;
  }

  // SIGINT/SIGTERM/SIGHUP arrive through a signalfd the main thread polls; every thread
  // started from here on inherits the blocked mask.
  sigset_t sigs;
  sigemptyset(&sigs);
  sigaddset(&sigs, SIGINT);
  sigaddset(&sigs, SIGTERM);
  sigaddset(&sigs, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &sigs, nullptr);
  signal(SIGPIPE, SIG_IGN);
  const int sfd = signalfd(-1, &sigs, SFD_CLOEXEC | SFD_NONBLOCK);

  LogSink sink(stderr);
  Logger log(sink, "mocapd", cfg->daemon.log_level);

  if (!o.replay.empty())
    return run_replay_daemon(o.replay, o.speed, o.config.empty() ? nullptr : &*cfg, sets, sfd, log);

  // One instance per runtime directory: the lock comes before any device, port or shared
  // memory is touched, so a second mocapd changes nothing.
  std::unique_ptr<InstanceLock> instance;
  try {
    const std::string sock =
        cfg->daemon.control_socket.empty() ? default_control_socket() : cfg->daemon.control_socket;
    const auto slash = sock.find_last_of('/');
    instance = std::make_unique<InstanceLock>(slash == std::string::npos ? std::string(".")
                                              : slash == 0               ? std::string("/")
                                                                         : sock.substr(0, slash));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mocapd: %s\n", e.what());
    return 1;
  }

  try {
    LiveSetup live = make_live(*cfg, o.demo, log);
    Daemon d(live.cfg, std::move(live.parts), log);
    d.start();
    d.wait(sfd);
    signalfd_siginfo si{};
    if (::read(sfd, &si, sizeof si) == static_cast<ssize_t>(sizeof si))
      log.info("signal %u: shutting down", si.ssi_signo);
    else
      log.info("quit requested: shutting down");
    d.shutdown();
  } catch (const std::exception& e) {
    log.error("%s", e.what());
    return 1;
  }
  ::close(sfd);
  return 0;
}
