// mocapd: the motion-capture daemon. Parses the command line, loads and validates the
// configuration, assembles the daemon (daemon_setup.hpp) and runs until SIGINT/SIGTERM or
// `mocapctl quit`; or replays a recorded session through the same pipeline.
#include <signal.h>
#include <sys/signalfd.h>
#include <unistd.h>

#include <cstdio>
#include <memory>
#include <string>

#include "mocap/core/cli_args.hpp"
#include "mocap/daemon/config.hpp"
#include "mocap/daemon/daemon.hpp"
#include "mocap/daemon/daemon_setup.hpp"
#include "mocap/daemon/instance_lock.hpp"

using namespace mocap;
using namespace mocap::daemon;

namespace {

const char* kUsage =
    "usage: mocapd [--config FILE | --demo] [--set KEY=VALUE ...] [options]\n"
    "       mocapd --check-config FILE [--set KEY=VALUE ...]\n"
    "       mocapd --print-config [--config FILE] [--set KEY=VALUE ...]\n"
    "       mocapd --replay SESSION [--speed 0|1|X] [--config FILE]\n"
    "options:\n";

}  // namespace

int main(int argc, char** argv) {
  CliArgs args;
  args.flag("help", "show this help")
      .flag("version", "print the version")
      .option("config", "rig configuration (TOML)")
      .option("check-config", "validate a configuration file and exit")
      .flag("print-config", "print the effective configuration (defaults included) and exit")
      .flag("print-config-reference",
            "print the configuration keys' reference (markdown, as in docs/configuration.md)")
      .multi("set", "override a configuration key, e.g. --set outputs.json.port=7400")
      .flag("demo", "run the virtual performer's simulated sensors (config/demo.toml rig)")
      .option("replay", "play a recorded session through the pipeline and exit")
      .option("speed", "replay speed: 1 = real time (default), 0 = as fast as possible, X = factor")
      .option("log-level", "daemon log level (overrides daemon.log_level)");
  if (!args.parse(argc, argv)) {
    std::fprintf(stderr, "mocapd: %s\n", args.error().c_str());
    return 2;
  }
  if (args.has("version")) {
    std::printf("mocapd 0.1.0\n");
    return 0;
  }
  if (args.has("help") || !args.positional().empty()) {
    std::printf(
        "%s%sconfiguration keys (--set SECTION.KEY=VALUE; --print-config-reference "
        "describes each):\n%s",
        kUsage, args.help().c_str(), config_key_summary().c_str());
    return args.has("help") ? 0 : 2;
  }
  if (args.has("print-config-reference")) {
    std::printf("%s", config_reference_markdown().c_str());
    return 0;
  }
  std::vector<std::string> sets = args.get_all("set");
  if (auto lvl = args.get("log-level")) sets.push_back("daemon.log_level=" + *lvl);

  // Configuration: --check-config FILE, --config FILE, or the demo rig.
  const bool check = args.has("check-config");
  std::string config_path = check ? *args.get("check-config") : args.get_or("config", "");
  if (check && args.has("config")) {
    std::fprintf(stderr, "mocapd: give --check-config FILE or --config FILE, not both\n");
    return 2;
  }
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
  if (!check && !args.has("demo") && !args.has("replay") && !args.has("print-config") &&
      cfg->sensors.empty()) {
    std::fprintf(stderr,
                 "mocapd: no sensors configured: give --config RIG.toml (see config/) or --demo\n");
    return 2;
  }
  if (check) {
    std::printf("%s: OK (%zu sensor%s)\n", config_path.c_str(), cfg->sensors.size(),
                cfg->sensors.size() == 1 ? "" : "s");
    return 0;
  }
  if (args.has("print-config")) {
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

  if (auto replay = args.get("replay")) {
    double speed = 1.0;
    if (!args.get_double("speed", speed) || speed < 0) {
      std::fprintf(stderr, "mocapd: --speed needs a number >= 0\n");
      return 2;
    }
    return run_replay_daemon(*replay, speed, args.has("config") ? &*cfg : nullptr, sets, sfd, log);
  }

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
    LiveSetup live = make_live(*cfg, args.has("demo"), log);
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
