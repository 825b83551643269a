// Motions with known ground truth for the virtual performer: built-in procedural clips (N-pose
// calibration stand, walk cycle, turn in place, squat, arm raises through 90 degrees of shoulder
// elevation, reaching) and sequences of them. A Motion gives the pelvis orientation and every
// joint rotation as a smooth (C2) function of time; MotionTrack adds the pelvis translation from
// foot contact (the lower ankle stays planted) and optional looping.
#pragma once

#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "mocap/sim/body_pose.hpp"

namespace mocap::sim {

class Motion {
 public:
  virtual ~Motion() = default;
  /// Length of the motion, seconds.
  virtual double duration_s() const = 0;
  /// Pelvis orientation and joint rotations at t_s in [0, duration_s()]. If
  /// has_root_translation() is false the pelvis position is left for MotionTrack to fill.
  virtual void pose(double t_s, BodyPose& out) const = 0;
  /// True when the motion carries its own pelvis trajectory (e.g. motion capture data).
  virtual bool has_root_translation() const { return false; }
  /// Interval [start, end] in seconds during which the performer stands still in the N-pose
  /// (the calibration pose). Every built-in motion starts with one.
  virtual std::pair<double, double> calibration_window_s() const { return {0.0, 0.0}; }
  /// Body dimensions the motion was made for (e.g. a BVH file's bone lengths); nullptr: any.
  virtual const BodyDimensions* dimensions() const { return nullptr; }
};

/// A BVH file as motion input (via the skeleton's BvhMotion): `prelude` if given (a motion
/// without root translation that starts and ends in the N-pose, e.g. the calibration procedure;
/// played facing the clip's first heading, its feet planted where the N-pose puts them), a
/// `lead_in_s` N-pose stand, a smooth `blend_s` transition into the first frame, then the clip,
/// interpolated with Catmull-Rom (C1) so the virtual accelerometers see finite accelerations.
/// The calibration window is the prelude's, else the lead-in. Carries its own root trajectory
/// and the file's body dimensions. session_s longer than the clip: the clip is played back and
/// forth (forward, then backward along the same path, easing through zero speed over 1 s at
/// each turn) until the played part lasts at least session_s: a long session, in which the
/// sensors' drift grows as it does on a person for that long. Throws std::runtime_error for
/// unreadable or unrecognisable files.
std::unique_ptr<Motion> make_bvh_motion(const std::string& path, double lead_in_s = 3.0,
                                        double blend_s = 1.0,
                                        std::shared_ptr<const Motion> prelude = nullptr,
                                        double session_s = 0);

/// Names accepted by make_motion: "npose", "walk", "turn", "squat", "arm_raise", "reach" (each
/// preceded by a 3 s N-pose stand and followed by a 1 s stand) and "sequence" (all of them
/// strung together: stand, walk, turn, walk back, turn, squat, arm raises, reach).
std::span<const std::string_view> motion_names();

/// The built-in motion of that name, or a BVH file for a name ending in ".bvh"
/// (make_bvh_motion); throws std::invalid_argument naming the valid names (std::runtime_error
/// for an unreadable file). "calibrate+<name>" (e.g. "calibrate+squat", "calibrate+take.bvh"):
/// the 3 s N-pose stand, then the calibration moves (two shallow knee bends with elbow curls,
/// 4 s, then a 1 s stand: calibration_moves_s() in all), then the motion without its own
/// leading stand. "warmup+<name>" (built-in motions, e.g. "warmup+calibrate+walk"): 22.4 s of
/// walking there and back first, as when a person puts the sensors on and walks in; the
/// calibration window is the stand after it. "session<S>+<file>.bvh" (e.g.
/// "session600+calibrate+take.bvh"): the clip played back and forth for at least S seconds
/// (make_bvh_motion's session_s).
std::unique_ptr<Motion> make_motion(std::string_view name);

/// Duration of the calibration moves including their closing 1 s stand, seconds.
double calibration_moves_s();

/// A motion placed in the world: adds the pelvis translation (feet planted: the weight-bearing
/// ankle stays fixed on the floor, blended smoothly between feet) and optionally loops forever
/// (each loop continues from where the previous one ended). Precomputes the root trajectory at
/// construction; pose() does not allocate.
class MotionTrack {
 public:
  MotionTrack(std::shared_ptr<const Motion> motion, const BodyDimensions& dims, bool loop);
  /// Full body pose at performer time t_s >= 0 (clamped to the end when not looping).
  void pose(double t_s, BodyPose& out) const;
  const Motion& motion() const { return *motion_; }
  double period_s() const { return motion_->duration_s(); }

 private:
  void local_pose(double t_s, BodyPose& out) const;  // within one period, root from the table
  Eigen::Vector3d root_velocity(double t_s) const;   // horizontal, from the planted feet
  struct Contacts {
    Eigen::Vector3d p[4];  // heel_l, toe_l, heel_r, toe_r relative to the pelvis, earth axes
    double w[4];           // share of the weight on each
    double z_m;            // pelvis height that puts the weighted contact on the floor
  };
  void contacts(const BodyPose& orientations, Contacts& out) const;

  std::shared_ptr<const Motion> motion_;
  BodyDimensions dims_;
  bool loop_;
  double ankle_height_m_ = 0;
  double grid_s_ = 0.005;
  std::vector<Eigen::Vector3d> root_xy_;  // integrated horizontal pelvis position on the grid
  double loop_yaw_rad_ = 0;               // heading change over one period
  Eigen::Vector3d loop_shift_m_ = Eigen::Vector3d::Zero();  // root displacement over one period
};

}  // namespace mocap::sim
