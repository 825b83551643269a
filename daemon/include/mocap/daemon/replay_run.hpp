// The engine and pipeline of a replay, set up in one place for `mocapd --replay` and `mocap
// replay`: the configuration (a rig, or the recorded one changed by --set), the session's own
// calibration, and frames flagged kFrameReplay.
#pragma once

#include <string>
#include <vector>

#include "mocap/core/log.hpp"
#include "mocap/daemon/config.hpp"
#include "mocap/daemon/pipeline_core.hpp"
#include "mocap/daemon/replay.hpp"
#include "mocap/daemon/rig_engine.hpp"

namespace mocap::daemon {

/// The configuration a replay of `src` runs with: src.config(), which is the rig the source was
/// opened with when rig_given, else the input's own (recorded, or the segment-named sensors of a
/// CSV) with `sets` (KEY=VALUE) applied. A replay calibrates at once when asked (the input is the
/// countdown) and never writes the live calibration file. Throws std::runtime_error with the
/// problems of `sets`.
Config replay_config(const SampleSource& src, bool rig_given, const std::vector<std::string>& sets,
                     const std::string& input);

/// A replay's engine and pipeline core for `cfg` (from replay_config). session_calibration:
/// start from the calibration stored with the input, if any.
struct ReplayRun {
  ReplayRun(Config cfg, const SampleSource& src, const std::string& input, bool session_calibration,
            Logger* log = nullptr);
  const Config cfg;  ///< engine and core keep references into it
  RigEngine engine;
  PipelineCore core;
};

}  // namespace mocap::daemon
