// Which orientation of a sensor to give the skeleton while its magnetometer is disturbed: the
// filter's 6-D orientation (gyro + accelerometer, heading from the gyro only) turned by the last
// trusted heading offset between its 9-D and 6-D outputs, instead of the 9-D orientation.
//
// Why: a magnet or steel near a segment bends the field the filter takes its heading from.
// AttitudeFilter flags the field as disturbed but, in its first ~9 s (the initial heading
// convergence, gain 1/n) and after its rejection budget (60 s), still follows it; the calibration
// then absorbs one field direction and the segment turns with every other one (elbow and knee
// errors of 14-23 deg next to the magnet, docs/accuracy.md). Holding the offset while the flag is
// up keeps the segment on the gyro; when the flag clears the offset slews back to the filter's
// at a bounded rate, so a field change does not jump the avatar. The offset is held from the
// first sample (a magnet present from start-up is never "trusted"); AttitudeFilter flags every
// sensor until its first reference field (~5 s), so clean sensors ride on the gyro for those
// seconds too and pick up its bias drift: a measured trade-off, hence off by default.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>

namespace mocap {

struct HeadingHoldOptions {
  bool enabled = false;     ///< opt-in: see docs/accuracy.md for what it gains and costs
  double slew_deg_s = 2.0;  ///< largest rate the held offset follows the filter's once trusted
};

/// One per sensor. Allocation-free, deterministic.
class HeadingHold {
 public:
  explicit HeadingHold(HeadingHoldOptions o = {}) : opt_(o) {}
  /// The orientation to use. q_earth_sensor_9d / _6d: the filter's outputs; mag_disturbed: its
  /// flag (held while set); t_ns: sample time.
  Eigen::Quaterniond update(const Eigen::Quaterniond& q_earth_sensor_9d,
                            const Eigen::Quaterniond& q_earth_sensor_6d, bool mag_disturbed,
                            int64_t t_ns);
  /// Heading offset in use (9-D minus 6-D heading), rad.
  double offset_rad() const { return offset_rad_; }
  bool holding() const { return holding_; }
  void reset() { started_ = false; }

 private:
  HeadingHoldOptions opt_;
  bool started_ = false, holding_ = false;
  double offset_rad_ = 0;
  int64_t t_last_ns_ = 0;
};

}  // namespace mocap
