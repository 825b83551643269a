// The daemon's PoseEngine: a rig config turned into the one body tracker (rig::BodyTracker),
// plus what only a running daemon needs: the calibration file (loaded at start, saved by a
// writer thread, CalibrationSaver, whenever the calibration in use changes; the pipeline never
// waits for the disk), log lines and the status's calibration message.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "mocap/daemon/calibration_saver.hpp"
#include "mocap/daemon/config.hpp"
#include "mocap/daemon/pose_engine.hpp"
#include "mocap/rig/body_tracker.hpp"

namespace mocap::daemon {

/// The body tracker's sensors and options for a rig config.
std::vector<rig::TrackerSensor> tracker_sensors(const Config& cfg);
rig::TrackerOptions tracker_options(const Config& cfg);

class RigEngine final : public PoseEngine {
 public:
  static constexpr double kSaveEveryS = 5.0;  ///< at most one calibration save per this

  /// Builds the tracker for the config's sensors; loads calibration.file if it exists.
  /// Throws std::runtime_error on an unreadable calibration or body file.
  explicit RigEngine(const Config& cfg, Logger* log = nullptr);
  /// Writes a calibration still waiting for the disk.
  ~RigEngine() override;

  void on_sample(int sensor_index, const ImuSample& sample) override;
  /// The filter/track split (BodyTracker::filter_sample, track_sample): not while a
  /// calibration capture runs.
  bool prefilter_allowed() const override { return !tracker_.capturing(); }
  FilterOutput prefilter(int sensor_index, const ImuSample& sample) override;
  void on_prefiltered(int sensor_index, const ImuSample& sample, const FilterOutput& o) override;
  void set_sensor_live(int sensor_index, bool live) override;
  void build_frame(int64_t t_ns, PoseFrame& out) override;
  SensorHealth sensor_health(int sensor_index) const override {
    return tracker_.sensor_health(sensor_index);
  }
  CalibrationProgress calibration_progress() const override;
  void calibrate(CalibrationPose pose, bool mounting_motion) override;
  void reset_heading() override;

  /// The outcome of the last calibration capture ("" while none finished).
  const std::string& last_calibration_message() const { return calib_message_; }
  rig::BodyTracker& tracker() { return tracker_; }
  const Skeleton& skeleton() const { return tracker_.skeleton(); }
  const AttitudeFilter& filter(int sensor) const { return tracker_.filter(sensor); }
  /// Blocks until every calibration handed to the writer thread so far is on disk.
  void flush_calibration_file();

 private:
  /// After a sample: a calibration capture that ended is logged (and saved).
  void after_sample(const ImuSample& s);
  Config cfg_;
  Logger* log_;
  rig::BodyTracker tracker_;
  std::string calib_message_;
  uint64_t saved_revision_ = 0;     ///< skeleton calibration revision last saved (or loaded)
  int64_t saved_t_ns_ = INT64_MIN;  ///< sample time of that save
  std::unique_ptr<CalibrationSaver> saver_;  ///< null without calibration.file
  void save_calibration_file(int64_t t_ns);
};

}  // namespace mocap::daemon
