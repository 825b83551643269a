// Axis remapping from a device's axes to the rig's sensor frame ("x,y,z", "-y,x,z", ...), applied
// after unit conversion to every vector (and to the device's own orientation estimate).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <string_view>

namespace mocap {

class AxisRemap {
 public:
  AxisRemap() = default;
  /// Parses "x,y,z"-style text: three comma-separated axes, each optionally negated, a
  /// permutation of x, y, z, right-handed. Throws std::invalid_argument naming the problem.
  static AxisRemap parse(std::string_view text);

  /// sensor[i] = sign[i] * device[index[i]].
  Eigen::Vector3d apply(const Eigen::Vector3d& device) const {
    return Eigen::Vector3d(sign_[0] * device[idx_[0]], sign_[1] * device[idx_[1]],
                           sign_[2] * device[idx_[2]]);
  }
  /// A rotation q_ref_device re-expressed as q_ref_sensor (right-multiplied by q_device_sensor).
  Eigen::Quaterniond apply(const Eigen::Quaterniond& q_ref_device) const {
    return q_ref_device * q_device_sensor_;
  }
  bool identity() const { return identity_; }

 private:
  std::array<int, 3> idx_{0, 1, 2};
  std::array<double, 3> sign_{1, 1, 1};
  Eigen::Quaterniond q_device_sensor_ = Eigen::Quaterniond::Identity();
  bool identity_ = true;
};

}  // namespace mocap
