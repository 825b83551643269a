// The assembled daemon: configuration -> devices -> pipeline (engine) -> outputs, plus the
// control socket and the recording. mocapd's main() builds one and waits for a signal or `quit`.
#pragma once

#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "mocap/core/log.hpp"
#include "mocap/core/wakeup.hpp"
#include "mocap/daemon/config.hpp"
#include "mocap/daemon/control.hpp"
#include "mocap/daemon/pipeline.hpp"
#include "mocap/drivers/device.hpp"
#include "mocap/outputs/recorder.hpp"

namespace mocap::daemon {

/// Makes a live device for a spec (mocapd passes mocap::make_device).
using DeviceFactory = std::function<std::unique_ptr<Device>(const DeviceSpec&, Logger)>;

/// Something running beside the pipeline for the daemon's lifetime (e.g. the demo's simulated
/// devices). Started before the devices are opened, stopped after they are closed.
class Service {
 public:
  virtual ~Service() = default;
  virtual void start(Pipeline& pipeline) = 0;
  virtual void stop() = 0;
};

/// The sensors of a config as the pipeline sees them.
std::vector<SensorInfo> sensor_infos(const Config& cfg);
/// The DeviceSpec of sensor i of a config (its device index and sensor id are i). SlimeVR
/// trackers on one port share a device: the spec of the group's first sensor maps them all
/// (options "trackers" = "MAC/SENSOR=INDEX@AXIS_REMAP;...").
DeviceSpec device_spec(const Config& cfg, size_t i);
/// The sensor whose device carries sensor i's samples: i itself, or the first SlimeVR sensor
/// on the same port.
size_t device_leader(const Config& cfg, size_t i);

class Daemon {
 public:
  struct Parts {
    std::unique_ptr<PoseEngine> engine;
    DeviceFactory device_factory;                         ///< null: no devices are opened
    std::unique_ptr<outputs::Recorder> recorder;          ///< null: recording unavailable
    std::vector<std::unique_ptr<outputs::Output>> sinks;  ///< outputs (streams, posture)
    std::vector<std::unique_ptr<Service>> services;       ///< e.g. the demo's simulated devices
    uint32_t frame_flags = 0;                             ///< e.g. kFrameDemo
  };
  Daemon(Config cfg, Parts parts, Logger log);
  ~Daemon();

  /// Opens devices, starts the pipeline and the control socket. Throws on failure.
  void start();
  /// Blocks until stop is requested (quit command, request_stop, signal fd readable).
  void wait(int extra_fd = -1);
  void request_stop() { stop_.notify(); }
  /// Stops devices and pipeline, closes the recording. Idempotent.
  void shutdown();

  /// Handles one control request; returns the JSON reply line.
  std::string handle(const ControlRequest& r);
  std::string status_json() const;
  Pipeline& pipeline() { return *pipeline_; }
  const std::string& control_path() const { return control_path_; }

 private:
  void update_device_counters();

  Config cfg_;
  Parts parts_;
  Logger log_;
  std::unique_ptr<Pipeline> pipeline_;
  std::vector<std::unique_ptr<Device>> devices_;
  std::unique_ptr<ControlServer> control_;
  std::string control_path_;
  Wakeup stop_;
  int64_t started_ns_ = 0;
  mutable std::mutex rec_mu_;
  std::string recording_path_;
  bool running_ = false;
};

}  // namespace mocap::daemon
