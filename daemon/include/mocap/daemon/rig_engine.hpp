// The real PoseEngine: one AttitudeFilter per sensor, the skeleton's Calibrator for N-/T-pose
// captures, and the Skeleton solver (forward kinematics, joint limits, root motion). The
// calibration in use (the pose capture refined from knee/elbow motion, heading resets) is saved
// to calibration.file whenever it changes, at most every kSaveRefinedEveryS of sample time, by
// a writer thread (CalibrationSaver): the pipeline never waits for the disk.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "mocap/daemon/calibration_saver.hpp"
#include "mocap/daemon/config.hpp"
#include "mocap/daemon/pose_engine.hpp"
#include "mocap/filter/attitude_filter.hpp"
#include "mocap/filter/rig_field_consensus.hpp"
#include "mocap/skeleton/calibration.hpp"
#include "mocap/skeleton/skeleton.hpp"

namespace mocap::daemon {

/// The filter parameters of a config (filter.* keys applied to the defaults).
FilterParams filter_params(const FilterConfig& f);

class RigEngine final : public PoseEngine {
 public:
  static constexpr double kSaveRefinedEveryS = 5.0;

  /// Builds filters and skeleton for the config's sensors; loads calibration.file if it exists.
  /// Throws std::runtime_error on an unreadable calibration or body file.
  explicit RigEngine(const Config& cfg, Logger* log = nullptr);
  /// Writes a calibration still waiting for the disk.
  ~RigEngine() override;

  void on_sample(int sensor_index, const ImuSample& sample) override;
  void set_sensor_live(int, bool) override {}
  void build_frame(int64_t t_ns, PoseFrame& out) override;
  SensorFilterState sensor_state(int sensor_index) const override;
  CalibrationProgress calibration_progress() const override;
  void calibrate(CalibrationPose pose) override;
  void reset_heading() override;

  /// The outcome of the last calibration capture ("" while none finished).
  const std::string& last_calibration_message() const { return calib_message_; }
  Skeleton& skeleton() { return skeleton_; }
  const AttitudeFilter& filter(int sensor) const { return filters_[sensor]; }
  /// Blocks until every calibration handed to the writer thread so far is on disk.
  void flush_calibration_file();

 private:
  Config cfg_;
  Logger* log_;
  std::vector<AttitudeFilter> filters_;
  filt::RigFieldConsensus consensus_;  ///< reference field shared by the rig's sensors
  std::vector<int> segment_of_;
  std::vector<Eigen::Vector3d> gyr_scale_;  ///< per sensor: [[sensor]] gyr_scale, or 1
  Skeleton skeleton_;
  Calibrator calibrator_;
  int64_t newest_t_ns_ = 0;
  std::string calib_message_;
  uint64_t saved_revision_ = 0;     ///< skeleton calibration revision last saved (or loaded)
  int64_t saved_t_ns_ = INT64_MIN;  ///< sample time of that save
  std::unique_ptr<CalibrationSaver> saver_;  ///< null without calibration.file
  void save_calibration_file(int64_t t_ns);
};

}  // namespace mocap::daemon
