// Where the viewer's poses come from: the local daemon's shared posture, a procedural demo, a
// played-back file or a network stream. One PoseFrame per avatar.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <string>
#include <vector>

#include "mocap/skeleton/body_model.hpp"
#include "mocap/skeleton/pose_frame.hpp"

namespace mocap::viewer {

class PoseSource {
 public:
  virtual ~PoseSource() = default;
  /// Updates `frames` (one per avatar) to the pose at viewer time `t_s` (seconds since the
  /// viewer started; headless runs step it by a fixed frame time). Returns true if the frames
  /// changed. Never blocks.
  virtual bool poll(double t_s, std::vector<PoseFrame>& frames) = 0;
  /// One line for the heads-up display ("shared posture /mocap-posture-1000", "waiting ...").
  virtual std::string status() const = 0;
  /// Playback control; live sources ignore it.
  virtual bool seekable() const { return false; }
  virtual void set_paused(bool) {}
  virtual void seek_by(double /*dt_s*/) {}
  /// Body proportions the poses were made with (a file's own skeleton), or nullptr to use the
  /// viewer's (--body-height).
  virtual const BodyDimensions* dimensions() const { return nullptr; }
};

/// A file played back on a clock of its own: pause and seek move the playback position, which
/// the file source maps to one of its frames.
class PlaybackSource : public PoseSource {
 public:
  bool seekable() const override { return true; }
  void set_paused(bool paused) override { paused_ = paused; }
  void seek_by(double dt_s) override { position_s_ += dt_s; }

 protected:
  /// Advances the playback position to viewer time t_s (unless paused) and returns it.
  double advance(double t_s) {
    if (!paused_) position_s_ += t_s - last_t_s_;
    last_t_s_ = t_s;
    return position_s_;
  }

 private:
  bool paused_ = false;
  double position_s_ = 0, last_t_s_ = 0;
};

/// Fills a PoseFrame's earth orientations and joint positions from joint rotations
/// (q_parent_segment, pelvis = q_earth_pelvis) and the pelvis position, by forward kinematics
/// over the body dimensions. Leaves flags and sensors untouched.
void pose_from_joint_rotations(const BodyDimensions& dims,
                               const std::array<Eigen::Quaternionf, kSegmentCount>& q_parent,
                               const Eigen::Vector3f& p_earth_pelvis_m, PoseFrame& out);

/// N-pose standing at `p_floor_m` (pelvis above it at the reference height), facing +x.
PoseFrame reference_pose(const BodyDimensions& dims, const Eigen::Vector3f& p_floor_m);

}  // namespace mocap::viewer
