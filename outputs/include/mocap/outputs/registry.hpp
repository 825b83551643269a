// The outputs the daemon can run, one row each: its name, the configuration section that enables
// it, and the factory that builds and starts it from its options. Adding an output is its file
// (an Output with a factory), its options struct in outputs_config.hpp, its keys in the daemon's
// key table, and one row in src/registry.cpp. The recorder is no row: the control socket starts
// and stops it (recorder.hpp); replay's file writers are made by `mocap replay` itself.
#pragma once

#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "mocap/core/log.hpp"
#include "mocap/outputs/output.hpp"
#include "mocap/outputs/outputs_config.hpp"

namespace mocap::outputs {

/// What an output may need beyond its own section.
struct OutputContext {
  int realtime_priority = 0;  ///< SCHED_FIFO priority for an output's I/O thread (0 = normal)
  double model_height_m = 0;  ///< the body model's height (VRChat's position scale)
  Logger* log = nullptr;      ///< where an output reports what it opened (may be null)
};

struct OutputRow {
  std::string_view name;     ///< e.g. "json"
  std::string_view section;  ///< the configuration section, e.g. "outputs.json"
  bool (*enabled)(const OutputsConfig&);
  /// Builds and starts the output; throws std::runtime_error naming what failed.
  std::unique_ptr<Output> (*make)(const OutputsConfig&, const OutputContext&);
};

/// Every output, in the order the daemon builds them (and hands them each frame).
std::span<const OutputRow> output_rows();

/// Creates and starts every enabled output. Throws std::runtime_error starting with the section
/// (e.g. "outputs.json: ...") when one cannot start (e.g. its port is taken): the daemon never
/// runs half-configured.
std::vector<std::unique_ptr<Output>> make_outputs(const OutputsConfig& cfg,
                                                  const OutputContext& ctx);

}  // namespace mocap::outputs
