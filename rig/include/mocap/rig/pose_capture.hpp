// The still-pose capture of a calibration. The person stands in a known pose (N-pose or T-pose)
// for ~2 s; each sensor's orientation (in its own filter's earth frame) and specific force are
// averaged, and the capture is judged: enough samples, nobody moved, the attitude agrees with
// gravity. What it yields, PoseCapture, is an immutable input to the alignment
// (alignment.hpp): each mounting's tilt comes from it (the segment's up axis in its sensor's
// frame), each mounting yaw is referred to it, and nothing changes it afterwards.
//
// Running sums only (sum of q q^T for the mean and spread, sum of earth-frame specific force):
// add_sample never allocates.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>

#include "mocap/core/segments.hpp"
#include "mocap/skeleton/calibration.hpp"
#include "mocap/skeleton/rig.hpp"

namespace mocap::rig {

struct PoseCaptureOptions {
  double capture_s = 2.0;                ///< capture duration
  double min_sample_fraction = 0.5;      ///< each sensor needs >= this * capture_s * 10 Hz samples
  double max_motion_deg = 2.0;           ///< refuse if a sensor's RMS spread exceeds this
  double max_gravity_error_deg = 5.0;    ///< refuse if attitude and accelerometer disagree more
  double max_acc_norm_error_m_s2 = 0.8;  ///< refuse if |acc| departs this far from g (moving)
};

/// What a capture saw, per segment with a sensor.
struct PoseCapture {
  CalibrationPose pose = CalibrationPose::npose;
  int64_t t_end_ns = 0;                    ///< newest sample time in the capture
  std::array<bool, kSegmentCount> have{};  ///< the segment has a sensor in the rig
  /// Mean orientation of the segment's sensor, in the sensor's own filter frame (9D: the shared
  /// earth frame; 6D: a heading of its own).
  std::array<Eigen::Quaterniond, kSegmentCount> q_earth_sensor;
  std::array<double, kSegmentCount> motion_deg{};         ///< RMS orientation spread
  std::array<double, kSegmentCount> gravity_error_deg{};  ///< tilt vs accelerometer, -1 without
  std::array<int, kSegmentCount> samples{};
  double worst_motion_deg = 0, worst_gravity_error_deg = 0;

  PoseCapture() { q_earth_sensor.fill(Eigen::Quaterniond::Identity()); }
  /// The earth's up axis in the segment's sensor frame: the segment's up axis in the pose (the
  /// part of each mounting a still pose determines).
  Eigen::Vector3d up_sensor(int segment) const {
    return q_earth_sensor[segment].conjugate() * Eigen::Vector3d::UnitZ();
  }
};

/// Collects a capture's samples and judges it.
class PoseCapturer {
 public:
  explicit PoseCapturer(RigMapping rig, PoseCaptureOptions options = {});

  /// Starts a capture in `pose`; samples before t_start_ns are ignored.
  void start(CalibrationPose pose, int64_t t_start_ns);
  /// One orientation sample of the sensor on `segment` (its filter's frame); acc_sensor_m_s2
  /// optional (specific force in the sensor frame) for the gravity check.
  void add_sample(int segment, const Eigen::Quaterniond& q_earth_sensor, int64_t t_ns,
                  const Eigen::Vector3d* acc_sensor_m_s2 = nullptr);
  bool capturing() const { return capturing_; }
  /// Fraction of the capture elapsed at t_ns (0..1).
  double progress(int64_t t_ns) const;
  bool done(int64_t t_ns) const { return capturing_ && progress(t_ns) >= 1.0; }

  struct Result {
    bool ok = false;
    PoseCapture capture;
    std::string message;  ///< why it was refused, naming the segments and what to do
  };
  /// Ends the capture and judges it.
  Result finish();
  const PoseCaptureOptions& options() const { return opt_; }

 private:
  struct Accum {
    Eigen::Matrix4d qq = Eigen::Matrix4d::Zero();
    Eigen::Vector3d acc_earth = Eigen::Vector3d::Zero();
    double acc_norm_max_dev = 0;
    int n = 0, n_acc = 0;
  };
  RigMapping rig_;
  PoseCaptureOptions opt_;
  CalibrationPose pose_ = CalibrationPose::npose;
  bool capturing_ = false;
  int64_t t_start_ns_ = 0, t_last_ns_ = 0;
  std::array<Accum, kSegmentCount> acc_{};
};

}  // namespace mocap::rig
