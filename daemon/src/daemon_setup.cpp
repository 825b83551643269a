// Builds the live daemon's parts (engine, devices, demo, outputs, recorder) and runs the
// daemon's replay mode.
#include "mocap/daemon/daemon_setup.hpp"
#include "mocap/daemon/prefetch_source.hpp"

#include <poll.h>

#include "mocap/daemon/demo.hpp"
#include "mocap/daemon/outputs.hpp"
#include "mocap/daemon/recorder.hpp"
#include "mocap/daemon/replay.hpp"
#include "mocap/daemon/rig_engine.hpp"
#include "mocap/skeleton/calibration.hpp"

namespace mocap::daemon {

Daemon::Parts make_live_parts(Config& cfg, bool demo, Logger& log) {
  Daemon::Parts parts;
  if (demo) {
    parts.services.push_back(make_demo(cfg, log.child("demo", log.level())));
    parts.frame_flags |= kFrameDemo;
    log.info("demo: %zu simulated sensors (%s path, %s protocol, motion '%s')", cfg.sensors.size(),
             std::string(to_string(cfg.demo.path)).c_str(), cfg.demo.protocol.c_str(),
             cfg.demo.motion.c_str());
  }
  parts.engine = std::make_unique<RigEngine>(cfg, &log);
  if (!(demo && cfg.demo.path == DemoPath::direct))
    parts.device_factory = [](const DeviceSpec& spec, Logger l) {
      return make_device(spec, std::move(l));
    };
  parts.sinks = make_outputs(cfg, log);
  // The calibration text is read on the control thread while the pipeline may change it: the
  // recorder stores the calibration file's content when there is one.
  const std::string calib_file = cfg.calibration.file;
  parts.recorder = std::make_unique<SessionRecorder>(
      cfg,
      [calib_file]() -> std::string {
        if (calib_file.empty()) return {};
        try {
          return serialize_calibration(load_calibration(calib_file));
        } catch (const std::exception&) {
          return {};
        }
      },
      log.child("recorder", log.level()));
  return parts;
}

int run_replay_daemon(const std::string& path, double speed, const Config* rig,
                      const std::vector<std::string>& sets, int signal_fd, Logger& log) {
  try {
    std::unique_ptr<SampleSource> src =
        std::make_unique<PrefetchSource>(open_sample_source(path, rig));
    Config cfg = src->config();
    if (!rig) {
      ConfigErrors errs;
      std::optional<Config> changed = with_overrides(cfg, sets, path + " (configuration)", errs);
      if (!changed) {
        log.error("%s", errs.to_string().c_str());
        return 1;
      }
      cfg = *changed;
    }
    // A replay uses the session's own calibration and never writes the live calibration file.
    cfg.calibration.file.clear();
    RigEngine engine(cfg, &log);
    if (const std::string ct = src->calibration_text(); !ct.empty())
      engine.tracker().set_calibration(parse_calibration(ct, path + " (calibration)"));
    PipelineCore core(cfg.pipeline, cfg.calibration, sensor_infos(cfg), engine);
    core.set_frame_flag(kFrameReplay, true);
    auto sinks = make_outputs(cfg, log);
    for (auto& s : sinks)
      core.add_sink(s.get());
    ReplayOptions opt;
    opt.speed = speed;
    opt.cancelled = [signal_fd] {
      pollfd p{signal_fd, POLLIN, 0};
      return ::poll(&p, 1, 0) > 0;
    };
    log.info("replaying %s (%zu sensors) at speed %g", path.c_str(), cfg.sensors.size(), speed);
    const ReplayResult r = run_replay(*src, core, opt);
    log.info("replay %s: %llu samples, %llu frames, %.1f s of session",
             r.cancelled ? "cancelled" : "done", static_cast<unsigned long long>(r.samples),
             static_cast<unsigned long long>(r.frames), (r.t_last_ns - r.t_first_ns) * 1e-9);
    return 0;
  } catch (const std::exception& e) {
    log.error("replay: %s", e.what());
    return 1;
  }
}

}  // namespace mocap::daemon
