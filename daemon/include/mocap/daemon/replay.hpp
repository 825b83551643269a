// Offline and daemon replay: a recorded session (raw bytes through the drivers' decoders, or
// the recorded samples) or a CSV of samples, played through the same PipelineCore and engine as
// the live daemon, on the recorded timestamps (sample-time frame clock, no wall clock in the
// computation): the same input gives bit-identical poses every time.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "mocap/daemon/config.hpp"
#include "mocap/daemon/pipeline_core.hpp"
#include "mocap/daemon/pose_engine.hpp"

namespace mocap::daemon {

/// A time-ordered stream of samples with the rig they belong to.
class SampleSource {
 public:
  virtual ~SampleSource() = default;
  /// The rig (sensor i = sample.sensor_id i).
  virtual const Config& config() const = 0;
  /// Next sample; false at the end or on an error (then error() is non-empty).
  virtual bool next(ImuSample& out) = 0;
  virtual const std::string& error() const = 0;
  /// Fraction of the input consumed (0..1) for progress bars.
  virtual double progress() const = 0;
  /// Calibration text stored with the input ("" if none).
  virtual std::string calibration_text() const { return {}; }
  /// CLOCK_REALTIME minus the samples' clock when they were recorded, in force at the last
  /// sample returned (sessions record it); false if unknown (CSV).
  virtual bool unix_offset_ns(int64_t& /*out*/) const { return false; }
};

enum class SessionSource { automatic, raw, samples };

/// Opens a session file. rig: optional config that replaces the recorded one (its sensors must
/// match the recorded sensors by name). Throws std::runtime_error naming the file and problem.
std::unique_ptr<SampleSource> open_session_source(const std::string& path, const Config* rig,
                                                  SessionSource source = SessionSource::automatic);
/// Opens a CSV of samples (sample_csv.hpp). With a rig, CSV sensor names must be rig sensor
/// names; without, a sensor named like a segment drives that segment. Throws on errors.
std::unique_ptr<SampleSource> open_csv_source(const std::string& path, const Config* rig);
/// Session or CSV by content (session files start with the magic "MOCAPSES").
std::unique_ptr<SampleSource> open_sample_source(const std::string& path, const Config* rig);

struct ReplayOptions {
  double speed = 0;  ///< 0 = as fast as possible, 1 = real time, X = X times real time
  std::optional<CalibrationPose> calibrate_pose;  ///< calibrate at calibrate_at_s into the input
  double calibrate_at_s = 0;
  /// The calibration is an N-pose followed by the mounting motion (mocapctl calibrate mounting).
  bool calibrate_mounting_motion = false;
  std::function<bool()> cancelled;               ///< polled now and then (signals)
  std::function<void(double)> progress;          ///< called about 10 times a second of work
  std::function<void(int64_t)> on_first_sample;  ///< the input's first sample time
  /// > 0 (and speed 0): the filters of different sensors run on this many threads besides the
  /// replay's own, a chunk of samples ahead of the rest of the pipeline (PoseEngine::prefilter;
  /// sequential while a calibration is asked for or captured). The frames are the same, bit
  /// for bit.
  int filter_threads = 0;
};

struct ReplayResult {
  uint64_t samples = 0;
  uint64_t frames = 0;
  int64_t t_first_ns = 0, t_last_ns = 0;
  bool cancelled = false;
};

/// Plays every sample of `src` through `core` (which holds the engine and sinks).
ReplayResult run_replay(SampleSource& src, PipelineCore& core, const ReplayOptions& opt);
/// run_replay's path with opt.filter_threads (daemon/src/replay_parallel.cpp).
ReplayResult run_replay_parallel(SampleSource& src, PipelineCore& core, const ReplayOptions& opt);

}  // namespace mocap::daemon
