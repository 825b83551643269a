// `mocapd --demo`: the virtual performer's 15 sensors as a Service. Device path (default): each
// sensor's samples are encoded into its wire protocol and written to its own pseudo-terminal,
// which the daemon opens with the real driver like any serial sensor. Direct path: samples go
// straight into the pipeline (no encoding, no ptys).
#pragma once

#include <memory>

#include "mocap/core/log.hpp"
#include "mocap/daemon/config.hpp"
#include "mocap/daemon/daemon.hpp"

namespace mocap::daemon {

/// Fills cfg.sensors with the performer's 15 sensors (named after their segments) and returns
/// the service that produces their data. Device path: the sensors' ports are the ptys it made.
/// Throws std::runtime_error / std::invalid_argument (e.g. unknown motion or protocol).
std::unique_ptr<Service> make_demo(Config& cfg, Logger log);

}  // namespace mocap::daemon
