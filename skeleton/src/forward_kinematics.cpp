// Forward kinematics over the parent chain (depth-first order: parents come first).
#include "mocap/skeleton/forward_kinematics.hpp"

#include "mocap/skeleton/quat_math.hpp"

namespace mocap {

void pose_from_earth_orientations(const BodyDimensions& dims,
                                  const std::array<Eigen::Quaterniond, kSegmentCount>& q_earth,
                                  const Eigen::Vector3d& p_root_m, PoseFrame& out) {
  std::array<Eigen::Vector3d, kSegmentCount> p;
  for (int s = 0; s < kSegmentCount; ++s) {
    const int par = kSegmentParent[s];
    p[s] = par < 0 ? p_root_m : Eigen::Vector3d(p[par] + q_earth[par] * dims.joint_offset_m[s]);
    const Eigen::Quaterniond q_joint =
        par < 0 ? q_earth[s] : (q_earth[par].conjugate() * q_earth[s]).normalized();
    out.q_earth_segment[s] = to_wxyz(q_earth[s]);
    out.q_parent_segment[s] = to_wxyz(q_joint);
    out.p_earth_segment_m[s] = {static_cast<float>(p[s].x()), static_cast<float>(p[s].y()),
                                static_cast<float>(p[s].z())};
  }
}

}  // namespace mocap
