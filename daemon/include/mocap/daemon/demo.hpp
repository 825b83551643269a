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

/// The demo's rig and the service that produces its data.
struct Demo {
  /// The given configuration with the performer's 15 sensors (named after their segments;
  /// device path: their ports are the ptys the service made), a BVH motion's segment lengths,
  /// and the calibration fitted to the performer's N-pose stand.
  Config rig;
  std::unique_ptr<Service> service;
};
/// Throws std::runtime_error / std::invalid_argument (e.g. unknown motion or protocol).
Demo make_demo(const Config& cfg, Logger log);

}  // namespace mocap::daemon
