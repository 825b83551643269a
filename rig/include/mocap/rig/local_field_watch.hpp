// 9D: a sensor whose filter took a local field for north at the calibration. A magnet or steel
// near a sensor turns the field about the vertical and keeps its norm and dip: no test of one
// filter can tell it from the earth's. The calibration finds it as a sensor whose facing is far
// off the body heading (calibrate.hpp); if its field looks like the earth's (norm near the
// rig's median) the tracker watches it here: the segment's heading is held (the filter's 6D
// output with the heading offset it had) until the field's heading in the 6D frame has turned
// by about the suspected amount, at least half of it within a few seconds (the person walked
// away; the 6D frame's drift is far slower). Then the mounting turns by what the field turned
// (Alignment::turn_mounting) and the held heading turns with it, and on with the field's further
// turn (low-passed), until the filter's own heading (slow to leave the local field) has caught
// up; then the filter's 9D output is used again. Given up after
// kHoldS with nothing changed. Data flows one way: the watch reads FilterOutput, never calls
// the filter.
#pragma once

#include <Eigen/Geometry>

#include "mocap/filter/attitude_filter.hpp"

namespace mocap::rig {

class LocalFieldWatch {
 public:
  static constexpr double kHoldS = 20.0;  ///< longest hold while the suspected field stays
  static constexpr double kStepS = 3.0;   ///< a turn counts as a step against its low-pass
  /// After a confirmation, the held heading is released once the filter's is this close, or
  /// after kFollowS.
  static constexpr double kReleaseDeg = 1.0;
  static constexpr double kFollowS = 60.0;

  /// Starts watching from the filter's present output: the turn the calibration suspects
  /// (rad, the body heading minus the sensor's facing). `norm_th`: the filter's relative field
  /// norm threshold (a field whose norm changes by more is not the same field turned).
  void suspect(double turn_rad, const FilterOutput& o, double norm_th);
  /// After a sample with a field: true once, when the field turned as suspected; `turned_rad`
  /// is then how far (the mounting turns by it).
  bool on_field(const FilterOutput& o, double dt_s, double& turned_rad);
  /// After every sample: ends the hold once the filter's heading has caught up.
  void on_sample(const FilterOutput& o, double dt_s);
  /// The sensor's orientation as the segment uses it: held, or the filter's 9D output.
  Eigen::Quaterniond q_earth_sensor(const FilterOutput& o) const;
  bool holding() const { return state_ != State::idle; }
  bool suspected() const { return state_ == State::suspect; }

 private:
  enum class State { idle, suspect, follow };
  State state_ = State::idle;
  double hold_rad_ = 0;  ///< heading offset applied to the 6D output while holding
  Eigen::Vector3d m0_uT_ = Eigen::Vector3d::Zero();  ///< the field when suspected (6D frame)
  double turn_rad_ = 0, t_s_ = 0, lp_rad_ = 0, norm_th_ = 0.1;
  /// Once confirmed: the held offset when suspected, and the field's turn since, low-passed.
  double suspect_hold_rad_ = 0, follow_rad_ = 0;
};

}  // namespace mocap::rig
