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

}  // namespace mocap
