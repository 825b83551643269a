// Forward kinematics shared by the viewer's procedural and file sources.
#include "mocap/viewer/pose_source.hpp"

namespace mocap::viewer {

void pose_from_joint_rotations(const BodyDimensions& dims,
                               const std::array<Eigen::Quaternionf, kSegmentCount>& q_parent,
                               const Eigen::Vector3f& p_earth_pelvis_m, PoseFrame& out) {
  std::array<Eigen::Quaternionf, kSegmentCount> q_earth;
  std::array<Eigen::Vector3f, kSegmentCount> p_earth;
  for (int s = 0; s < kSegmentCount; ++s) {
    const int parent = kSegmentParent[s];
    if (parent == kNoParent) {
      q_earth[s] = q_parent[s].normalized();
      p_earth[s] = p_earth_pelvis_m;
    } else {
      q_earth[s] = (q_earth[parent] * q_parent[s]).normalized();
      p_earth[s] = p_earth[parent] + q_earth[parent] * dims.joint_offset_m[s].cast<float>();
    }
    const Eigen::Quaternionf& qp = q_parent[s];
    out.q_earth_segment[s] = {q_earth[s].w(), q_earth[s].x(), q_earth[s].y(), q_earth[s].z()};
    out.q_parent_segment[s] = {qp.w(), qp.x(), qp.y(), qp.z()};
    out.p_earth_segment_m[s] = {p_earth[s].x(), p_earth[s].y(), p_earth[s].z()};
  }
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
