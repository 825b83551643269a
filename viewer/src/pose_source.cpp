// Joint rotations to a PoseFrame (through the skeleton's forward kinematics) and the rest pose,
// for the viewer's procedural and file sources.
#include "mocap/viewer/pose_source.hpp"

#include "mocap/skeleton/forward_kinematics.hpp"

namespace mocap::viewer {

void pose_from_joint_rotations(const BodyDimensions& dims,
                               const std::array<Eigen::Quaternionf, kSegmentCount>& q_parent,
                               const Eigen::Vector3f& p_earth_pelvis_m, PoseFrame& out) {
  std::array<Eigen::Quaterniond, kSegmentCount> q_earth;
  for (int s = 0; s < kSegmentCount; ++s) {
    const int parent = kSegmentParent[s];
    const Eigen::Quaterniond q = q_parent[s].cast<double>().normalized();
    q_earth[s] = parent == kNoParent ? q : (q_earth[parent] * q).normalized();
  }
  pose_from_earth_orientations(dims, q_earth, p_earth_pelvis_m.cast<double>(), out);
}

PoseFrame reference_pose(const BodyDimensions& dims, const Eigen::Vector3f& p_floor_m) {
  PoseFrame f;
  reset_pose(f);
  std::array<Eigen::Quaternionf, kSegmentCount> q;
  q.fill(Eigen::Quaternionf::Identity());
  const Eigen::Vector3f pelvis =
      p_floor_m + dims.joint_offset_m[index(Segment::pelvis)].cast<float>();
  pose_from_joint_rotations(dims, q, pelvis, f);
  return f;
}

}  // namespace mocap::viewer
