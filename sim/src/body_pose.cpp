// Ground-truth forward kinematics (independent of the skeleton solver under test).
#include "mocap/sim/body_pose.hpp"

#include "mocap/skeleton/quat_math.hpp"

namespace mocap::sim {

void truth_forward_kinematics(const BodyDimensions& dims, const BodyPose& pose, TruthFrame& out) {
  out.q_earth_segment[0] = pose.q_earth_pelvis.normalized();
  out.p_earth_segment_m[0] = pose.p_earth_pelvis_m;
  out.q_parent_segment[0] = out.q_earth_segment[0];
  for (int i = 1; i < kSegmentCount; ++i) {
    const int parent = kSegmentParent[i];
    const Eigen::Quaterniond q_joint = pose.q_parent_segment[i].normalized();
    out.q_parent_segment[i] = q_joint;
    out.q_earth_segment[i] = out.q_earth_segment[parent] * q_joint;
    out.p_earth_segment_m[i] =
        out.p_earth_segment_m[parent] + out.q_earth_segment[parent] * dims.joint_offset_m[i];
  }
}

PoseFrame to_pose_frame(const TruthFrame& t) {
  PoseFrame f;
  reset_pose(f);
  for (int s = 0; s < kSegmentCount; ++s) {
    f.q_earth_segment[s] = to_wxyz(t.q_earth_segment[s]);
    f.q_parent_segment[s] = to_wxyz(t.q_parent_segment[s]);
    const Eigen::Vector3d& p = t.p_earth_segment_m[s];
    f.p_earth_segment_m[s] = {static_cast<float>(p.x()), static_cast<float>(p.y()),
                              static_cast<float>(p.z())};
  }
  return f;
}

}  // namespace mocap::sim
