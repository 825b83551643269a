// Calibration poses and the names of poses and heading sources.
#include "mocap/skeleton/calibration.hpp"
#include "mocap/core/units.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <sstream>

#include "mocap/skeleton/quat_math.hpp"

namespace mocap {

namespace {

bool is_arm(int s) {
  return s == index(Segment::upper_arm_l) || s == index(Segment::forearm_l) ||
         s == index(Segment::hand_l) || s == index(Segment::upper_arm_r) ||
         s == index(Segment::forearm_r) || s == index(Segment::hand_r);
}
bool is_left_arm(int s) {
  return s == index(Segment::upper_arm_l) || s == index(Segment::forearm_l) ||
         s == index(Segment::hand_l);
}
}  // namespace

std::string_view to_string(CalibrationPose p) {
  return p == CalibrationPose::npose ? "npose" : "tpose";
}

std::string_view to_string(HeadingSource h) {
  switch (h) {
    case HeadingSource::pelvis_sensor:
      return "pelvis_sensor";
    case HeadingSource::mean_sensors:
      return "mean_sensors";
    case HeadingSource::explicit_heading:
      return "explicit_heading";
    case HeadingSource::arm_swing:
      return "arm_swing";
    case HeadingSource::mount_normals:
      return "mount_normals";
  }
  return "?";
}

Eigen::Quaterniond q_body_segment_in_pose(CalibrationPose pose, int segment) {
  if (pose == CalibrationPose::tpose && is_arm(segment))
    return axis_rotation(0, is_left_arm(segment) ? M_PI / 2 : -M_PI / 2);
  return Eigen::Quaterniond::Identity();
}

}  // namespace mocap
