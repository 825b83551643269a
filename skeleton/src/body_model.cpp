// Anthropometric body dimensions from height.
#include "mocap/skeleton/body_model.hpp"

namespace mocap {

BodyDimensions body_dimensions_from_height(double h) {
  BodyDimensions d;
  d.height_m = h;
  using V = Eigen::Vector3d;
  auto set = [&](Segment s, V joint, V end) {
    d.joint_offset_m[index(s)] = joint * h;
    d.end_offset_m[index(s)] = end * h;
  };
  // Heights above the floor (fractions of H): hip joints 0.530, waist 0.630, shoulders 0.818,
  // neck base 0.830, head (atlas) 0.880, top of head 1.000, elbow 0.632, wrist 0.486,
  // knee 0.285, ankle 0.039. Half widths: shoulders 0.110, hips 0.052.
  set(Segment::pelvis, V(0, 0, 0.530), V(0, 0, 0.100));
  set(Segment::torso, V(-0.010, 0, 0.100), V(0, 0, 0.200));
  set(Segment::neck, V(0, 0, 0.200), V(0.010, 0, 0.050));
  set(Segment::head, V(0.010, 0, 0.050), V(0.020, 0, 0.120));
  set(Segment::upper_arm_l, V(0, 0.110, 0.188), V(0, 0, -0.186));
  set(Segment::forearm_l, V(0, 0, -0.186), V(0, 0, -0.146));
  set(Segment::hand_l, V(0, 0, -0.146), V(0, 0, -0.108));
  set(Segment::upper_arm_r, V(0, -0.110, 0.188), V(0, 0, -0.186));
  set(Segment::forearm_r, V(0, 0, -0.186), V(0, 0, -0.146));
  set(Segment::hand_r, V(0, 0, -0.146), V(0, 0, -0.108));
  set(Segment::thigh_l, V(0, 0.052, 0), V(0, 0, -0.245));
  set(Segment::shank_l, V(0, 0, -0.245), V(0, 0, -0.246));
  set(Segment::foot_l, V(0, 0, -0.246), V(0.110, 0, -0.039));
  set(Segment::thigh_r, V(0, -0.052, 0), V(0, 0, -0.245));
  set(Segment::shank_r, V(0, 0, -0.245), V(0, 0, -0.246));
  set(Segment::foot_r, V(0, 0, -0.246), V(0.110, 0, -0.039));
  return d;
}

std::array<Eigen::Vector3d, kSegmentCount> reference_joint_positions(const BodyDimensions& d) {
  std::array<Eigen::Vector3d, kSegmentCount> p{};
  for (int i = 0; i < kSegmentCount; ++i) {
    const int parent = kSegmentParent[i];
    p[i] = parent == kNoParent ? d.joint_offset_m[i] : p[parent] + d.joint_offset_m[i];
  }
  return p;
}

}  // namespace mocap
