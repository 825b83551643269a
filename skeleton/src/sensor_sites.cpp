// The standard sensor sites' outward normals (see sensor_sites.hpp).
#include "mocap/skeleton/sensor_sites.hpp"

namespace mocap {

Eigen::Vector3d standard_site_normal_body(Segment s) {
  using V = Eigen::Vector3d;
  const bool left = s == Segment::upper_arm_l || s == Segment::forearm_l || s == Segment::hand_l ||
                    s == Segment::thigh_l;
  const double side = left ? 1.0 : -1.0;  // lateral: +y on the left, -y on the right
  switch (s) {
    case Segment::pelvis:
    case Segment::neck:
      return -V::UnitX();
    case Segment::torso:
    case Segment::shank_l:
    case Segment::shank_r:
      return V::UnitX();
    case Segment::upper_arm_l:
    case Segment::upper_arm_r:
    case Segment::forearm_l:
    case Segment::forearm_r:
    case Segment::hand_l:
    case Segment::hand_r:
      return side * V::UnitY();
    case Segment::thigh_l:
    case Segment::thigh_r:
      return V(1, 0.4 * side, 0).normalized();
    case Segment::head:
    case Segment::foot_l:
    case Segment::foot_r:
      break;
  }
  return V::UnitZ();
}

Eigen::Vector3d standard_site_position_m(Segment seg, const BodyDimensions& dims) {
  using V = Eigen::Vector3d;
  const double s = dims.height_m / 1.75;
  const V end = dims.end_offset_m[index(seg)];
  const double side = standard_site_normal_body(seg).y() > 0.1 ? 1.0 : -1.0;
  V r = V::Zero();
  switch (seg) {
    case Segment::pelvis:
      r = V(-0.10 * s, 0, 0.05 * s);
      break;
    case Segment::torso:
      r = V(0.11 * s, 0, 0.6 * end.z());
      break;
    case Segment::neck:
      r = V(-0.05 * s, 0, 0.5 * end.z());
      break;
    case Segment::head:
      r = V(0, 0, end.z() + 0.01 * s);
      break;
    case Segment::upper_arm_l:
    case Segment::upper_arm_r:
      r = V(0, side * 0.05 * s, 0.5 * end.z());
      break;
    case Segment::forearm_l:
    case Segment::forearm_r:
      r = V(0, side * 0.035 * s, 0.7 * end.z());
      break;
    case Segment::hand_l:
    case Segment::hand_r:
      r = V(0, side * 0.02 * s, 0.4 * end.z());
      break;
    case Segment::thigh_l:
    case Segment::thigh_r:
      r = V(0.07 * s, side * 0.03 * s, 0.5 * end.z());
      break;
    case Segment::shank_l:
    case Segment::shank_r:
      r = V(0.045 * s, 0, 0.4 * end.z());
      break;
    case Segment::foot_l:
    case Segment::foot_r:
      r = V(0.5 * end.x(), 0, -0.01 * s);
      break;
  }
  return r;
}

}  // namespace mocap
