// The shared setup of `mocapd --replay` and `mocap replay` (replay_run.hpp).
#include "mocap/daemon/replay_run.hpp"

#include <stdexcept>

#include "mocap/daemon/daemon.hpp"
#include "mocap/skeleton/calibration.hpp"

namespace mocap::daemon {

Config replay_config(const SampleSource& src, bool rig_given, const std::vector<std::string>& sets,
                     const std::string& input) {
  Config cfg = src.config();
  if (!rig_given) {
    ConfigErrors errs;
    std::optional<Config> changed = with_overrides(cfg, sets, input + " (configuration)", errs);
    if (!changed) {
      std::string text = errs.to_string();
      if (!text.empty() && text.back() == '\n') text.pop_back();
      throw std::runtime_error(text);
    }
    cfg = std::move(*changed);
  }
  cfg.calibration.countdown_s = 0;
  cfg.calibration.file.clear();
  return cfg;
}

ReplayRun::ReplayRun(Config c, const SampleSource& src, const std::string& input,
                     bool session_calibration, Logger* log)
    : cfg(std::move(c)),
      engine(cfg, log),
      core(cfg.pipeline, cfg.calibration, sensor_infos(cfg), engine) {
  if (const std::string ct = src.calibration_text(); session_calibration && !ct.empty())
    engine.tracker().set_calibration(parse_calibration(ct, input + " (calibration)"));
  core.set_frame_flag(kFrameReplay, true);
}

}  // namespace mocap::daemon
