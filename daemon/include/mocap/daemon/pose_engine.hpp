// The per-sample processing the pipeline drives, behind a small interface: per-sensor attitude
// filters, sensor-to-segment calibration and the skeleton solver. The pipeline owns threads,
// timing, health and outputs; an engine owns the math. RigEngine (rig_engine.hpp) is the real
// one (filter + skeleton); tests may plug in their own.
#pragma once

#include <array>
#include <cstdint>

#include "mocap/core/imu_sample.hpp"
#include "mocap/filter/attitude_filter.hpp"
#include "mocap/rig/facing.hpp"
#include "mocap/rig/sensor_health.hpp"
#include "mocap/skeleton/calibration.hpp"
#include "mocap/skeleton/pose_frame.hpp"

namespace mocap::daemon {

/// The reference pose of a calibration (the skeleton module's enum).
using CalibrationPose = mocap::CalibrationPose;

/// One segment's alignment as the status reports it (rig/alignment.hpp): where its mounting
/// and its heading came from (rig::AlignSource) and how sure each is.
struct SegmentAlignmentStatus {
  rig::AlignSource mounting_source = rig::AlignSource::none;
  rig::AlignSource heading_source = rig::AlignSource::none;
  float mounting_sigma_deg = 180, heading_sigma_deg = 180;
  uint32_t rejected_turns = 0;   ///< turns from motion refused as implausible
  uint32_t corrected_turns = 0;  ///< far turns accepted as a wrong first facing's correction
  bool heading_lost = false;     ///< its own heading frame lost (a dropout), not yet found again
  uint32_t lost_headings = 0;    ///< how often that happened
};

/// How far the calibration has got (for the status): the last capture's outcome, whether the
/// mounting motion is being watched, and each segment's alignment. Fixed size: the pipeline
/// copies it with every status snapshot.
struct CalibrationProgress {
  std::array<char, 256> message{};  ///< last capture's outcome, NUL-terminated ("" if none)
  bool mounting_motion = false;     ///< the mounting motion's window is open
  std::array<SegmentAlignmentStatus, kSegmentCount> segments{};
};

/// One sensor's health (rig/sensor_health.hpp): produced once by the engine.
using rig::SensorHealth;

class PoseEngine {
 public:
  virtual ~PoseEngine() = default;
  /// One sample of sensor `sensor_index` (index in the rig). Must not allocate.
  virtual void on_sample(int sensor_index, const ImuSample& sample) = 0;
  /// Optional: on_sample in two steps, so that offline replay can run the filters of different
  /// sensors on other threads (daemon/replay.cpp). prefilter() is the part that touches only
  /// that sensor's state (its filter): callable from any thread, for different sensors at
  /// once, ahead of on_prefiltered() of earlier samples; on_prefiltered() is the rest, in
  /// sample order on the pipeline thread. Only while prefilter_allowed(). An engine without
  /// the split returns false from prefilter_allowed().
  virtual bool prefilter_allowed() const { return false; }
  virtual FilterOutput prefilter(int /*sensor_index*/, const ImuSample& /*sample*/) { return {}; }
  virtual void on_prefiltered(int sensor_index, const ImuSample& sample, const FilterOutput&) {
    on_sample(sensor_index, sample);
  }
  /// A sensor became silent (live = false) or came back; its segment is then inferred.
  virtual void set_sensor_live(int sensor_index, bool live) = 0;
  /// Fills the pose part of `out` (segment orientations, positions, joints, violations,
  /// segment_flags, kFrameCalibrated) from the current state. Must not allocate.
  virtual void build_frame(int64_t t_ns, PoseFrame& out) = 0;
  virtual SensorHealth sensor_health(int sensor_index) const = 0;
  /// The calibration's progress; engines without calibration report none.
  virtual CalibrationProgress calibration_progress() const { return {}; }
  /// Takes the current sensor orientations as the given reference pose; with mounting_motion
  /// (an N-pose) the mounting motion follows it (rig/mounting_motion.hpp).
  virtual void calibrate(CalibrationPose pose, bool mounting_motion) = 0;
  /// Re-aligns the heading so the performer faces +x (east) now.
  virtual void reset_heading() = 0;
};

}  // namespace mocap::daemon
