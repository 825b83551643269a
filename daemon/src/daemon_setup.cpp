// Builds the live daemon's parts (engine, devices, demo, outputs, recorder) and runs the
// daemon's replay mode.
#include "mocap/daemon/daemon_setup.hpp"
#include "mocap/daemon/prefetch_source.hpp"

#include <poll.h>

#include <ctime>

#include "mocap/core/segments.hpp"
#include "mocap/core/time.hpp"
#include "mocap/daemon/demo.hpp"
#include "mocap/daemon/replay_run.hpp"
#include "mocap/daemon/rig_engine.hpp"
#include "mocap/outputs/recorder.hpp"
#include "mocap/outputs/registry.hpp"
#include "mocap/skeleton/calibration.hpp"

namespace mocap::daemon {

namespace {
/// The session header for a config: its effective TOML, the sensor descriptions, the start times.
session::SessionHeader session_header(const Config& cfg, std::string calibration_text) {
  session::SessionHeader h;
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  h.t_start_unix_ns = static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
  h.t_start_host_ns = monotonic_ns();
  h.config_text = config_to_toml(cfg);
  h.calibration_text = std::move(calibration_text);
  for (size_t i = 0; i < cfg.sensors.size(); ++i) {
    session::SensorDescription d;
    d.name = cfg.sensors[i].name;
    d.protocol = cfg.sensors[i].driver;
    if (auto seg = segment_from_name(cfg.sensors[i].segment)) d.segment = index(*seg);
    d.device_index = static_cast<uint16_t>(i);
    h.sensors.push_back(d);
  }
  return h;
}

/// The enabled outputs of a config, from the outputs' registry (started).
std::vector<std::unique_ptr<outputs::Output>> make_outputs(const Config& cfg, Logger& log) {
  return outputs::make_outputs(cfg.outputs, {.realtime_priority = cfg.pipeline.realtime_priority,
                                             .model_height_m = cfg.body.model.height_m,
                                             .log = &log});
}
}  // namespace

LiveSetup make_live(const Config& given, bool demo, Logger& log) {
  LiveSetup live{given, {}};
  Config& cfg = live.cfg;
  Daemon::Parts& parts = live.parts;
  if (demo) {
    Demo d = make_demo(given, log.child("demo", log.level()));
    cfg = std::move(d.rig);
    parts.services.push_back(std::move(d.service));
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
  parts.recorder = std::make_unique<outputs::SessionRecorder>(
      cfg.recording,
      [cfg, calib_file]() {
        std::string calibration_text;
        if (!calib_file.empty()) {
          try {
            calibration_text = serialize_calibration(load_calibration(calib_file));
          } catch (const std::exception&) {
          }
        }
        return session_header(cfg, std::move(calibration_text));
      },
      log.child("recorder", log.level()));
  return live;
}

int run_replay_daemon(const std::string& path, double speed, const Config* rig,
                      const std::vector<std::string>& sets, int signal_fd, Logger& log) {
  try {
    std::unique_ptr<SampleSource> src =
        std::make_unique<PrefetchSource>(open_sample_source(path, rig));
    ReplayRun run(replay_config(*src, rig != nullptr, sets, path), *src, path, true, &log);
    const Config& cfg = run.cfg;
    auto sinks = make_outputs(cfg, log);
    for (auto& s : sinks)
      run.core.add_sink(s.get());
    ReplayOptions opt;
    opt.speed = speed;
    opt.cancelled = [signal_fd] {
      pollfd p{signal_fd, POLLIN, 0};
      return ::poll(&p, 1, 0) > 0;
    };
    log.info("replaying %s (%zu sensors) at speed %g", path.c_str(), cfg.sensors.size(), speed);
    const ReplayResult r = run_replay(*src, run.core, opt);
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
