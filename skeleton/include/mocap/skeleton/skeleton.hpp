// The skeleton solver: per-segment earth-frame sensor orientations in, a whole-body posture
// (PoseFrame) out. Forward kinematics as in the thesis's Figure 29: each segment's orientation
// comes from its own sensor through the calibration (q_correction q_earth_sensor
// q_sensor_segment, nothing else: a segment is never worse than its own sensor's filter, except
// for the ease below while an alignment found while tracking turns it);
// positions follow the parent chain by the joint offsets; segments without a sensor are
// interpolated between tracked neighbours along their chain (e.g. torso between pelvis and neck) or
// follow their parent. Joint rotations are checked against swing-twist/hinge limits and violations
// reported per joint, never clamped (real people exceed textbook ranges: docs/skeleton.md); the
// root moves with the stance foot or is pinned. The solve never changes the calibration; only
// set_calibration does (the body tracker's alignment owns it: rig/alignment.hpp). An alignment
// found while tracking (set_calibration with ease) changes the calibration at once, but each
// segment's published orientation turns onto it at SkeletonOptions::ease_deg_s, never in one
// frame: a heading found from motion 60-160 deg off, applied at once, snapped a segment over
// between two frames, which a user sees as a flip (and a recorded take or a BVH export keeps).
//
// Per-frame work (set_sensor_orientation, solve) never allocates, and is deterministic: identical
// inputs give bit-identical frames.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <limits>

#include "mocap/skeleton/body_model.hpp"
#include "mocap/skeleton/calibration.hpp"
#include "mocap/skeleton/joint_limits.hpp"
#include "mocap/skeleton/pose_frame.hpp"
#include "mocap/skeleton/rig.hpp"
#include "mocap/skeleton/root_motion.hpp"

namespace mocap {

struct SkeletonOptions {
  RootMotionOptions root{};
  /// A segment whose newest sample is older than this (relative to the newest of all) is stale:
  /// its last orientation is held and kSegStale set.
  int64_t stale_after_ns = 200'000'000;
  /// Time constant of the per-joint violation average (the drift signal), seconds.
  double violation_tau_s = 2.0;
  /// How fast a segment's published orientation turns onto an eased calibration change.
  double ease_deg_s = 360.0;
};

class Skeleton {
 public:
  Skeleton(const BodyModel& model, const JointLimits& limits, RigMapping rig,
           SkeletonOptions options = {});

  /// Applies a calibration (copies it). Without one, sensors are taken as aligned with their
  /// segments (q_sensor_segment = identity). ease: a change of the alignment in use (not a new
  /// calibration): each segment's published orientation turns onto it at options().ease_deg_s
  /// from where it was; otherwise, and for any turn still under way, at once.
  void set_calibration(const Calibration& c, bool ease = false);
  /// Segment s's orientation changes from `from` to `to` (earth frame) by no motion of its own
  /// (e.g. its sensor's orientation as the segment uses it switched source): the published one
  /// turns onto it at options().ease_deg_s, as for an eased calibration change.
  void ease_segment(int segment, const Eigen::Quaterniond& from, const Eigen::Quaterniond& to);
  /// The calibration in use (save this one).
  const Calibration& calibration() const { return calib_; }
  /// Counts every change of calibration() (set, heading reset): a caller that saves the
  /// calibration compares it with the value at its last save.
  uint64_t calibration_revision() const { return calib_revision_; }
  void clear_calibration() { set_calibration(Calibration{}); }
  /// The newest sensor orientation on `segment` (earth frame), and whether it is a live input
  /// (reported, its sensor not marked silent).
  const Eigen::Quaterniond& sensor_orientation(int segment) const { return q_es_[segment]; }
  bool sensor_live(int segment) const {
    return rig_.tracked(segment) && have_[segment] && !dead_[segment];
  }
  /// A silent sensor (live = false) stops driving its segment, which is then inferred, until
  /// it is marked live again. Sensors are live by default.
  void set_sensor_live(int segment, bool live);

  /// Newest orientation of the sensor on `segment` (earth frame) at t_ns. Non-finite or zero
  /// quaternions are rejected (counted in rejected_samples()). sensor_flags: SegmentFlag bits
  /// reported by the sensor's filter (kSegAtRest, kSegMagDisturbed), passed through to the
  /// frame.
  void set_sensor_orientation(int segment, const Eigen::Quaterniond& q_earth_sensor, int64_t t_ns,
                              uint32_t sensor_flags = 0);

  /// Solves the posture at the newest sample time. Fills every skeleton field of `out`
  /// (frame, t_ns, calibrated flag, orientations, positions, joint rotations, violations,
  /// segment flags); leaves out.sensors / sensor_count and the other frame flags to the caller.
  void solve(PoseFrame& out);
  /// Same, at an explicit time t_ns (staleness is judged against t_ns; out.t_ns = t_ns).
  void solve(int64_t t_ns, PoseFrame& out);

  /// Results of the last solve in double precision.
  const std::array<Eigen::Quaterniond, kSegmentCount>& q_earth_segment() const { return q_earth_; }
  const std::array<Eigen::Quaterniond, kSegmentCount>& q_parent_segment() const { return q_joint_; }
  const std::array<Eigen::Vector3d, kSegmentCount>& p_earth_segment_m() const { return p_earth_; }
  const std::array<JointCheck, kSegmentCount>& joint_checks() const { return checks_; }
  /// Exponential average of each joint's violation (degrees): a drift signal for the pipeline.
  const std::array<double, kSegmentCount>& violation_average_deg() const { return viol_avg_; }
  /// Largest violation_average_deg().
  double drift_signal_deg() const;
  uint64_t rejected_samples() const { return rejected_; }

  RootMotion& root_motion() { return root_; }
  const BodyModel& model() const { return model_; }
  const JointLimits& limits() const { return limits_; }
  const RigMapping& rig() const { return rig_; }
  const SkeletonOptions& options() const { return opt_; }

 private:
  /// Turns segment i's remaining ease towards identity by dt_s of easing; returns it.
  Eigen::Quaterniond ease_step(int i, double dt_s);

  BodyModel model_;
  JointLimits limits_;
  RigMapping rig_;
  SkeletonOptions opt_;
  Calibration calib_;  ///< as set (plus heading resets)
  /// Per segment, the rotation (earth frame, left of the calibrated orientation) still to be
  /// eased out of the published orientation (identity: none).
  std::array<Eigen::Quaterniond, kSegmentCount> q_ease_;
  uint64_t calib_revision_ = 0;
  RootMotion root_;

  // Inputs.
  std::array<Eigen::Quaterniond, kSegmentCount> q_es_;
  std::array<int64_t, kSegmentCount> t_in_ns_{};
  std::array<bool, kSegmentCount> have_{};
  std::array<bool, kSegmentCount> dead_{};
  std::array<uint32_t, kSegmentCount> in_flags_{};
  int64_t t_newest_ns_ = 0;
  int64_t t_prev_solve_ns_ = 0;
  uint64_t frame_ = 0;
  uint64_t rejected_ = 0;

  // Inference plan: for an untracked segment, the tracked segment down its chain and the
  // number of steps to it (0 = none).
  std::array<int8_t, kSegmentCount> chain_target_{};
  std::array<int8_t, kSegmentCount> chain_steps_{};

  // Outputs.
  std::array<Eigen::Quaterniond, kSegmentCount> q_earth_;
  std::array<Eigen::Quaterniond, kSegmentCount> q_joint_;
  std::array<Eigen::Vector3d, kSegmentCount> p_earth_;
  std::array<Eigen::Vector3d, kSegmentCount> p_rel_;
  std::array<JointCheck, kSegmentCount> checks_{};
  std::array<double, kSegmentCount> viol_avg_{};
};

/// The continuation of each segment's chain used to interpolate untracked segments:
/// torso->neck->head, upper arm->forearm->hand, thigh->shank->foot; -1 at chain ends.
inline constexpr std::array<int8_t, kSegmentCount> kChainChild = {1, 2,  3,  -1, 5,  6,  -1, 8,
                                                                  9, -1, 11, 12, -1, 14, 15, -1};

}  // namespace mocap
