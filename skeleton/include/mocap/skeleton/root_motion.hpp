// Root motion: moves the pelvis across the floor by keeping the stance foot's contact point
// fixed on the ground (floor at z = 0), or pins it. Each foot has two contact points, heel
// (below the ankle) and toe (the foot's end point); the stance foot is the lower foot with
// hysteresis, or the other foot as soon as the stance foot's heel or toe lifts off (toe-off
// timing: a real swing foot points toe-down and its toe leaves the floor moving forward), and
// its lower contact point is the anchor. Switching anchor re-anchors at the new point's current
// position, so the root never jumps. Vertical: the lowest contact point rests on the floor.
#pragma once

#include <Eigen/Geometry>
#include <array>

#include "mocap/core/segments.hpp"
#include "mocap/skeleton/body_model.hpp"

namespace mocap {

struct RootMotionOptions {
  bool pinned = false;  ///< true: the pelvis stays at pinned_position_m
  Eigen::Vector3d pinned_position_m = Eigen::Vector3d(0, 0, -1);  ///< z < 0: model pelvis height
  /// The other foot must be this much lower to take over. 3 cm: measured on the simulated
  /// performer's walk (1 cm switched too early at heel strike: 48 % root drift; 3 cm: 4 %).
  double stance_hysteresis_m = 0.03;
  bool floor_contact = true;  ///< keep the lowest contact point on the floor (z = 0)
  /// true: both contact points of a foot are its ankle projected to the sole (planted-ankle
  /// model, like the simulator); false: heel and toe points (rolling foot).
  bool ankle_contact = false;
  /// Toe-off timing (needs dt_s > 0 in update()): the other foot also takes over when it is
  /// lower by lift_gap_m and the gap opens faster than lift_rate_m_s (the stance foot's heel or
  /// toe is lifting off: a pitched swing foot leaves the floor at ~1 m/s), instead of waiting
  /// for stance_hysteresis_m, during which the anchor would ride on the lifting toe.
  /// lift_rate_m_s = 0: off.
  double lift_gap_m = 0.005;
  double lift_rate_m_s = 0.3;
};

class RootMotion {
 public:
  RootMotion(const BodyModel& model, RootMotionOptions options = {});

  /// p_rel: joint positions with the pelvis at the origin; q: earth-frame segment orientations.
  /// dt_s: time since the previous update (0: unknown, contact timing off for this frame).
  /// Returns the pelvis position in the earth frame. stance_foot: index of the stance foot
  /// segment (foot_l / foot_r).
  Eigen::Vector3d update(const std::array<Eigen::Vector3d, kSegmentCount>& p_rel,
                         const std::array<Eigen::Quaterniond, kSegmentCount>& q, double dt_s = 0);
  int stance_foot() const { return stance_foot_; }
  /// Places the pelvis at p_m (x, y; z is recomputed) and forgets the anchor.
  void reset(const Eigen::Vector3d& p_m = Eigen::Vector3d::Zero());
  const RootMotionOptions& options() const { return opt_; }

 private:
  Eigen::Vector3d heel_local_, toe_local_;
  RootMotionOptions opt_;
  double pelvis_height_m_;
  bool anchored_ = false;
  int stance_foot_ = index(Segment::foot_l);
  int anchor_point_ = 0;  ///< 0 heel, 1 toe
  Eigen::Vector2d anchor_xy_ = Eigen::Vector2d::Zero();
  Eigen::Vector3d root_m_ = Eigen::Vector3d::Zero();
  bool have_prev_ = false;
  double prev_gap_m_ = 0;  ///< previous frame's stance-foot height above the other foot
};

}  // namespace mocap
