// The virtual performer: a simulated person (motion + ground truth) wearing 15 virtual IMUs, one on
// every segment except the neck. Produces ImuSample streams through the same path real sensors use
// (mocapd --demo, mocap bench accuracy) and the ground truth to compare against.
//
// Sensor ids 0..14 map to the segments in segment order without the neck:
//   0 pelvis, 1 torso, 2 head, 3 upper_arm_l, 4 forearm_l, 5 hand_l, 6 upper_arm_r, 7 forearm_r,
//   8 hand_r, 9 thigh_l, 10 shank_l, 11 foot_l, 12 thigh_r, 13 shank_r, 14 foot_r.
// Sensor names are the segment names. Deterministic for a given seed and parameters.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "mocap/core/imu_sample.hpp"
#include "mocap/sim/body_pose.hpp"
#include "mocap/sim/motion.hpp"
#include "mocap/sim/sensor_model.hpp"

namespace mocap::sim {

struct PerformerParams {
  uint64_t seed = 1;
  double rate_hz = 100;             ///< per-sensor sample rate
  double height_m = 1.75;           ///< body dimensions from height (anthropometric ratios)
  std::string motion = "sequence";  ///< a make_motion() name (ignored when a Motion is given)
  bool loop = true;           ///< repeat the motion forever (the demo); else hold the last pose
  SensorModelParams sensor;   ///< error model, same for every sensor (draws differ per sensor)
  MagneticFieldParams field;  ///< earth field and local disturbances (disturbance_preset())
  int64_t t0_ns = 0;          ///< host time (t_host_ns) of performer time zero
};

class Performer {
 public:
  static constexpr int kSensorCount = 15;

  /// Throws std::invalid_argument for an unknown motion name or a rate <= 0.
  explicit Performer(const PerformerParams& params);
  /// Same with a caller-supplied motion (e.g. from a BVH file).
  Performer(const PerformerParams& params, std::shared_ptr<const Motion> motion);

  /// Appends every sample measured at or before t_host_ns (not yet returned), in time order.
  /// Samples lost in transport are skipped; the next one of that sensor carries kFlagGapBefore.
  /// Does not allocate once `out` has capacity for the samples due (reserve once).
  void step_to(int64_t t_host_ns, std::vector<ImuSample>& out);
  /// Ground truth at the time of the last step_to().
  const TruthFrame& truth() const { return truth_; }
  /// Ground truth at any performer time (seconds since t0).
  void truth_at(double t_s, TruthFrame& out) const;
  /// True motion of one sensor at performer time t_s (what an ideal IMU would see).
  SensorKinematics sensor_kinematics(int sensor_id, double t_s) const;

  static Segment sensor_segment(int sensor_id);
  static std::string_view sensor_name(int sensor_id) { return name(sensor_segment(sensor_id)); }
  /// Sensor id on a segment, -1 for the neck (no sensor).
  static int sensor_of(Segment s);

  const SensorMount& mount(int sensor_id) const { return mounts_[sensor_id]; }
  /// One sensor's drawn errors (biases, hard iron): truth for diagnostics.
  const SensorErrorModel& sensor_errors(int sensor_id) const { return errors_[sensor_id]; }
  const BodyDimensions& dims() const { return dims_; }
  const PerformerParams& params() const { return params_; }
  const MotionTrack& track() const { return track_; }
  /// Performer-time interval during which the performer stands in the N-pose.
  std::pair<double, double> calibration_window_s() const {
    return track_.motion().calibration_window_s();
  }

 private:
  void measure(int sensor_id, ImuSample& out);
  int64_t sample_time_ns(int sensor_id, uint32_t k);

  PerformerParams params_;
  BodyDimensions dims_;
  MotionTrack track_;
  std::array<SensorMount, kSensorCount> mounts_;
  std::vector<SensorErrorModel> errors_;  // one per sensor, sized at construction
  std::array<uint32_t, kSensorCount> next_k_{};
  std::array<int64_t, kSensorCount> next_t_ns_{};
  std::array<bool, kSensorCount> gap_{};
  TruthFrame truth_;
};

}  // namespace mocap::sim
