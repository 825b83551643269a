// The session recorder ([recording]): a RecordTap that forwards raw device bytes, samples and pose
// frames to a SessionWriter (which copies them into its ring; its own thread writes), and the
// Recorder interface the control socket starts and stops it through. Never blocks the pipeline or
// the device threads: a full ring drops a block and counts it.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>

#include "mocap/core/imu_sample.hpp"
#include "mocap/core/log.hpp"
#include "mocap/outputs/output.hpp"
#include "mocap/outputs/outputs_config.hpp"
#include "mocap/session/session_writer.hpp"

namespace mocap::outputs {

/// An Output that also receives what a recording needs from every thread: raw bytes from the
/// device threads, samples and frames from the pipeline thread. Implementations must not block.
class RecordTap : public Output {
 public:
  virtual void on_raw(uint16_t device_index, int64_t t_host_ns, std::span<const uint8_t> bytes) = 0;
  virtual void on_sample(const ImuSample& s) = 0;
};

/// What a finished recording holds (the `record stop` reply).
struct RecordingSummary {
  std::string path;
  double duration_s = 0;    ///< from start to stop (monotonic clock)
  uint64_t frames = 0;      ///< pose frames accepted
  uint64_t samples = 0;     ///< samples accepted
  uint64_t raw_blocks = 0;  ///< raw byte blocks accepted
  uint64_t drops = 0;       ///< blocks dropped (writer behind, or the recording had stopped)
  uint64_t bytes = 0;       ///< file size on disk, header included
  std::string error;        ///< why the recording stopped early ("" if it did not)
};

/// Starts and stops a recording (the session writer lives behind this).
class Recorder {
 public:
  virtual ~Recorder() = default;
  /// Creates a new file for `name` (see recording_file.hpp: exclusive, inside
  /// recording.directory; "" = a fresh take name; `unique`: a -N suffix instead of an error
  /// when the name is taken) and returns the tap to install, or throws std::runtime_error.
  virtual RecordTap* start(const std::string& name, bool unique) = 0;
  /// The file being recorded ("" when not recording).
  virtual std::string path() const = 0;
  /// Flushes and closes the current recording (after the tap was removed).
  virtual RecordingSummary stop() = 0;
  /// Non-empty if the recording stopped by itself (e.g. disk full).
  virtual std::string error() const { return {}; }
};

class SessionRecorder final : public Recorder, public RecordTap {
 public:
  /// header: called at each start for the session header (the configuration, the sensors, the
  /// calibration in force, the start times).
  SessionRecorder(RecordingConfig cfg, std::function<session::SessionHeader()> header, Logger log);
  ~SessionRecorder() override;

  RecordTap* start(const std::string& name, bool unique) override;
  std::string path() const override;
  RecordingSummary stop() override;
  std::string error() const override;

  void on_raw(uint16_t device_index, int64_t t_host_ns, std::span<const uint8_t> bytes) override;
  void on_sample(const ImuSample& s) override;
  void on_frame(const PoseFrame& f) override;

 private:
  RecordingConfig cfg_;
  std::function<session::SessionHeader()> header_;
  Logger log_;
  std::unique_ptr<SessionWriter> writer_;
  int64_t started_ns_ = 0;
  std::atomic<uint64_t> frames_{0}, samples_{0}, raw_blocks_{0};
};

}  // namespace mocap::outputs
