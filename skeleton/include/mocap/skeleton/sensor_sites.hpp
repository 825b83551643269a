// The standard sensor sites: where on each segment a sensor is strapped, given as the outward
// normal of the skin there in the body frame of the N-pose (x forward, y left, z up). A sensor
// lying flat on its site has its z axis along this normal; the calibration's mount_normals
// heading source (calibration.hpp) reads the body heading from those normals, and the virtual
// performer straps its sensors there (sim/sensor_model).
//
//   pelvis: sacrum (back, -x)          torso: sternum (front, +x)       neck: back of the neck
//   head: top (+z)                     upper arm, forearm, hand: lateral side (left +y, right -y)
//   thigh: front, turned 22 deg to the outside      shank: front of the tibia (+x)
//   foot: instep (+z)
#pragma once

#include <Eigen/Core>

#include "mocap/core/segments.hpp"
#include "mocap/skeleton/body_model.hpp"

namespace mocap {

/// Unit outward normal of the standard sensor site on `s` (body frame, N-pose).
Eigen::Vector3d standard_site_normal_body(Segment s);

/// Where the standard site is on `s`: the skin point in the segment's own frame (origin at its
/// joint, N-pose axes), metres, scaled to the body's dimensions.
Eigen::Vector3d standard_site_position_m(Segment s, const BodyDimensions& dims);

}  // namespace mocap
