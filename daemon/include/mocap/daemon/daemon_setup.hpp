// Assembling mocapd from a validated config: engine, devices (or the demo), outputs, recorder;
// and the daemon's replay mode. Used by mocapd's main() and the end-to-end tests.
#pragma once

#include <string>
#include <vector>

#include "mocap/core/log.hpp"
#include "mocap/daemon/config.hpp"
#include "mocap/daemon/daemon.hpp"

namespace mocap::daemon {

/// A live daemon's configuration and parts.
struct LiveSetup {
  Config cfg;  ///< the given one, or with demo the demo's rig (demo.hpp)
  Daemon::Parts parts;
};
/// The parts of a live daemon for `cfg`; demo: the virtual performer's sensors instead of the
/// configured ones, and kFrameDemo set. Throws std::runtime_error naming what failed.
LiveSetup make_live(const Config& cfg, bool demo, Logger& log);

/// `mocapd --replay FILE --speed X`: plays the session through the pipeline to the configured
/// outputs (frames flagged kFrameReplay), stopping early when signal_fd becomes readable.
/// rig: replaces the recorded config if given; otherwise `sets` (KEY=VALUE) change the recorded
/// one. Returns the exit code.
int run_replay_daemon(const std::string& path, double speed, const Config* rig,
                      const std::vector<std::string>& sets, int signal_fd, Logger& log);

}  // namespace mocap::daemon
