// The daemon's frame outputs as FrameSinks, built from the [outputs] config: the shared posture
// (viewer), the pose JSON stream (TCP, loopback by default) and VMC over OSC/UDP.
#pragma once

#include <memory>
#include <vector>

#include "mocap/core/log.hpp"
#include "mocap/daemon/config.hpp"
#include "mocap/daemon/pipeline_core.hpp"

namespace mocap::daemon {

/// Creates and starts every enabled output. Throws std::runtime_error naming the output and
/// address when one cannot start (e.g. the port is taken): the daemon never runs half-configured.
std::vector<std::unique_ptr<FrameSink>> make_outputs(const Config& cfg, Logger& log);

/// The TCP port the pose JSON stream among `outputs` listens on (the one picked when the
/// configured port is 0); 0 when there is none.
int json_stream_port(const std::vector<std::unique_ptr<FrameSink>>& outputs);

}  // namespace mocap::daemon
