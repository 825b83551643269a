// The single-threaded heart of the pipeline: sample -> engine, per-sensor health, calibration
// countdown and frame building/publishing. No clocks, no threads: the live Pipeline calls it
// with wall-clock times, replay with recorded times, so replay is deterministic.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "mocap/daemon/config.hpp"
#include "mocap/daemon/pose_engine.hpp"
#include "mocap/outputs/output.hpp"
#include "mocap/skeleton/pose_frame.hpp"

namespace mocap::daemon {

/// Static description of one rig sensor.
struct SensorInfo {
  std::string name;
  int segment = -1;  ///< Segment index or -1
};

/// Sensor connection states (SensorStatus::state). kDisconnected: it streamed, then its device
/// reported the link gone (a SlimeVR tracker silent for 3 s, a tracker that left its receiver,
/// an unplugged serial device) and nothing came since; kStale: silent, link not reported gone.
enum SensorState : uint8_t {
  kAbsent = 0,
  kConnecting = 1,
  kStreaming = 2,
  kStale = 3,
  kError = 4,
  kDisconnected = 5,
};

class PipelineCore {
 public:
  PipelineCore(const PipelineConfig& cfg, const CalibrationConfig& calib,
               std::vector<SensorInfo> sensors, PoseEngine& engine);

  /// Frame consumers, called on the thread that drives this core (live: must not block).
  void add_sink(outputs::Output* sink) { sinks_.push_back(sink); }
  PoseEngine& engine() { return engine_; }
  void remove_sink(outputs::Output* sink);

  /// One sample (sensor_id indexes the rig). Publishes a frame too in per-sample mode.
  void process(const ImuSample& s);
  /// process() for a sample whose filter step the engine already took (PoseEngine::prefilter
  /// gave `o`): offline replay with filters on other threads.
  void process(const ImuSample& s, const FilterOutput& o);
  /// False for a sample process() rejects (an unknown sensor, a non-finite value): it never
  /// reaches the engine, so it must not be prefiltered either.
  bool accepts(const ImuSample& s) const;
  /// A calibration countdown is running (its capture starts when it ends).
  bool calibrating() const { return calibrating_; }
  /// Builds and publishes a frame "now" (t_now_ns: ages and countdowns are relative to it).
  void publish_frame(int64_t t_now_ns);
  /// Sample-time frame clock (replay): publishes the frames due before time t_ns, one per
  /// period, so a replay produces the same frames as the rate it was recorded at.
  void advance_clock_to(int64_t t_ns);

  /// Starts a calibration: capture after the configured countdown (measured from t_now_ns).
  void request_calibration(CalibrationPose pose, int64_t t_now_ns, bool mounting_motion = false);
  void reset_heading() { engine_.reset_heading(); }
  /// Frame-level flags the pipeline does not own (recording, replay, demo).
  void set_frame_flag(uint32_t flag, bool on);
  /// CLOCK_REALTIME minus the samples' clock (ns): frames then carry t_unix_ns = t_ns + this.
  /// Live: sampled by the pipeline thread; replay: the recorded offset. Unset: t_unix_ns = 0.
  void set_unix_offset_ns(int64_t offset_ns) {
    unix_offset_ns_ = offset_ns;
    unix_offset_known_ = true;
  }

  /// Counters from outside the pipeline thread's view (device decoders, ring overflows).
  void set_external_counters(int sensor, uint32_t drops, uint32_t errors);
  void set_connected(int sensor, bool connected);

  const PoseFrame& last_frame() const { return frame_; }
  const std::vector<SensorInfo>& sensors() const { return sensors_; }
  CalibrationProgress calibration_progress() const { return engine_.calibration_progress(); }
  uint64_t samples_processed() const { return samples_; }
  uint64_t rejected_samples() const { return rejected_; }
  int64_t newest_sample_ns() const { return newest_t_ns_; }

 private:
  struct Health {
    int64_t last_t_ns = INT64_MIN;
    int64_t window_start_ns = INT64_MIN;
    uint32_t window_count = 0;
    float rate_hz = 0;
    uint32_t drops = 0, errors = 0;  // external counters
    uint32_t gaps = 0;               // samples flagged kFlagGapBefore
    int8_t link = -1;                // what its device reported: -1 nothing, 0 gone, 1 connected
    bool live = false;
    uint32_t seq = 0;         // the newest sample's ImuSample::seq
    int64_t t_device_ns = 0;  // and its device time
  };
  void maybe_finish_calibration(int64_t t_now_ns);
  /// process() up to the engine call, and after it.
  bool take(const ImuSample& s);
  void taken(const ImuSample& s);

  PipelineConfig cfg_;
  CalibrationConfig calib_;
  std::vector<SensorInfo> sensors_;
  PoseEngine& engine_;
  std::vector<outputs::Output*> sinks_;
  std::vector<Health> health_;
  PoseFrame frame_;
  uint64_t frame_no_ = 0, samples_ = 0, rejected_ = 0;
  int64_t newest_t_ns_ = 0;
  bool have_sample_ = false;            ///< newest_t_ns_ is a sample's time
  int64_t published_t_ns_ = INT64_MIN;  ///< time of the last frame published
  int64_t unix_offset_ns_ = 0;
  bool unix_offset_known_ = false;
  int64_t period_ns_;
  int64_t next_frame_ns_ = INT64_MIN;
  uint32_t extra_flags_ = 0;
  bool calibrating_ = false;
  bool state_changed_ = false;  ///< a flag or the calibration state changed since the last frame
  bool sample_since_frame_ = false;  ///< a sample was taken since the last frame
  CalibrationPose calib_pose_ = CalibrationPose::npose;
  bool calib_mounting_motion_ = false;
  int64_t calib_at_ns_ = 0;
};

}  // namespace mocap::daemon
