// Recording a session from the live pipeline: a RecordTap that forwards raw device bytes,
// samples and pose frames to a SessionWriter (non-blocking), and the Recorder the control
// socket starts and stops.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <string>

#include "mocap/daemon/config.hpp"
#include "mocap/daemon/daemon.hpp"
#include "mocap/session/session_writer.hpp"

namespace mocap::daemon {

/// The session header for a config: its effective TOML, the sensor descriptions.
session::SessionHeader session_header(const Config& cfg, std::string calibration_text);

class SessionRecorder final : public Recorder, public RecordTap {
 public:
  /// calibration_text: called at each start to store the calibration in force ("" if none).
  SessionRecorder(Config cfg, std::function<std::string()> calibration_text, Logger log);
  ~SessionRecorder() override;

  RecordTap* start(const std::string& name, bool unique) override;
  std::string path() const override;
  RecordingSummary stop() override;
  std::string error() const override;

  void on_raw(uint16_t device_index, int64_t t_host_ns, std::span<const uint8_t> bytes) override;
  void on_sample(const ImuSample& s) override;
  void on_frame(const PoseFrame& f) override;

 private:
  Config cfg_;
  std::function<std::string()> calibration_text_;
  Logger log_;
  std::unique_ptr<SessionWriter> writer_;
  int64_t started_ns_ = 0;
  std::atomic<uint64_t> frames_{0}, samples_{0}, raw_blocks_{0};
};

}  // namespace mocap::daemon
