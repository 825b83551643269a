// Assembling mocapd from a validated config: engine, devices (or the demo), outputs, recorder;
// and the daemon's replay mode. Used by mocapd's main() and the end-to-end tests.
#pragma once

#include <string>
#include <vector>

#include "mocap/core/log.hpp"
#include "mocap/daemon/config.hpp"
#include "mocap/daemon/daemon.hpp"

namespace mocap::daemon {

/// Parts of a live daemon. demo: cfg.sensors are replaced by the virtual performer's (see
/// demo.hpp) and kFrameDemo is set. Throws std::runtime_error naming what failed.
Daemon::Parts make_live_parts(Config& cfg, bool demo, Logger& log);

/// `mocapd --replay FILE --speed X`: plays the session through the pipeline to the configured
/// outputs (frames flagged kFrameReplay), stopping early when signal_fd becomes readable.
/// rig: replaces the recorded config if given; otherwise `sets` (KEY=VALUE) change the recorded
/// one. Returns the exit code.
int run_replay_daemon(const std::string& path, double speed, const Config* rig,
                      const std::vector<std::string>& sets, int signal_fd, Logger& log);

}  // namespace mocap::daemon
