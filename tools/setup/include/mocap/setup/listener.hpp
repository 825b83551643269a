// The devices `mocap setup` listens to: every candidate opened through the real drivers
// (make_device with the DeviceSpec mocapd would build from the same rig lines, so SlimeVR
// trackers on one port share one socket), feeding one MotionMeter; a candidate that stays silent
// is reopened with its next probe until one gives samples or none is left.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "mocap/core/log.hpp"
#include "mocap/daemon/config.hpp"
#include "mocap/drivers/device.hpp"
#include "mocap/setup/candidates.hpp"
#include "mocap/setup/motion_meter.hpp"

namespace mocap::setup {

class Listener {
 public:
  /// Candidate i's samples carry sensor id i.
  Listener(std::vector<Candidate> candidates, Logger log);
  ~Listener();
  Listener(const Listener&) = delete;
  Listener& operator=(const Listener&) = delete;

  /// Opens every candidate, waits `probe_s`, reopens the silent ones with their next probe,
  /// and so on; returns once every candidate gave samples or has no probe left, with the
  /// devices that gave nothing closed. `progress` is told of each reopening.
  void probe(double probe_s, const std::function<void(const std::string&)>& progress = {});
  /// Whether candidate i gave samples.
  bool heard(std::size_t i) const { return meter_.seen(i).samples > 0; }
  MotionMeter& meter() { return meter_; }
  const std::vector<Candidate>& candidates() const { return candidates_; }
  /// Stops every device (idempotent).
  void stop();

 private:
  void open(std::size_t leader);

  std::vector<Candidate> candidates_;
  daemon::Config cfg_;  ///< one sensor per candidate, named by its `what` (for log lines)
  Logger log_;
  MotionMeter meter_;
  std::map<std::size_t, std::unique_ptr<Device>> devices_;  ///< by leader sensor
};

}  // namespace mocap::setup
