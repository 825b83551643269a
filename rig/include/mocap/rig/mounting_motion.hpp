// The mounting motion: right after an N-pose capture the person bows and bends the knees twice
// with the elbows curling (SlimeVR's "mounting reset", our calibration moves). Every segment
// then tilts in its own sagittal plane, so the direction its up axis tilts toward, seen in its
// sensor's frame, is the segment's forward axis there, whatever the strap: a facing
// (facing.hpp) for any mounting, from gravity alone (no heading, no magnetometer). Thighs,
// forearms and hands swing their far ends forward (the up axis tilts to +x in their frame);
// the trunk and head lean and the shanks' tops go forward over the feet (to -x); the upper arms
// lean with the trunk. The feet stay flat: their facing comes from elsewhere.
//
// Per segment the tilt d = up(t) - up(capture), across the capture's up axis, is summed as
// sum(d |d|) (its direction, large tilts weighing most) and sum(d d^T) (its spread): a segment
// that tilted less than kMinTiltDeg, or not mostly one way, or not in one plane, gets no
// facing. The one-sigma is the spread's angle, at least kSigmaFloorDeg (a real bend is not
// exactly sagittal). add() never allocates.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>

#include "mocap/core/segments.hpp"
#include "mocap/rig/facing.hpp"
#include "mocap/rig/pose_capture.hpp"

namespace mocap::rig {

class MountingMotion {
 public:
  static constexpr double kMinTiltDeg = 6.0;
  static constexpr double kSigmaFloorDeg = 3.0;
  /// The tilts' resultant must carry this share of their summed squared size.
  static constexpr double kMinConsistency = 0.6;

  /// Starts watching the motion after `capture` for duration_s from t_start_ns.
  void start(const PoseCapture& capture, int64_t t_start_ns, double duration_s);
  bool active() const { return active_; }
  /// The window ended at t_ns: finish() gives the facings.
  bool done(int64_t t_ns) const { return active_ && t_ns >= t_end_ns_; }
  /// One orientation of the segment's sensor (any heading frame: only its up axis is used).
  void add(int segment, const Eigen::Quaterniond& q_earth_sensor, int64_t t_ns);
  /// Ends the window: each segment's facing at the capture (unknown where the motion did not
  /// show it).
  std::array<Facing, kSegmentCount> finish();
  /// The expected direction of the up axis' tilt in the segment's frame: +1 toward +x, -1
  /// toward -x, 0: the segment does not tilt (feet).
  static int tilt_sign(int segment);

 private:
  bool active_ = false;
  int64_t t_start_ns_ = 0, t_end_ns_ = 0;
  PoseCapture capture_;
  std::array<Eigen::Vector3d, kSegmentCount> up0_{};
  std::array<Eigen::Vector3d, kSegmentCount> sum_{};     ///< sum d |d|
  std::array<Eigen::Matrix3d, kSegmentCount> spread_{};  ///< sum d d^T
  std::array<double, kSegmentCount> max_tilt_{};         ///< largest |d|
};

}  // namespace mocap::rig
