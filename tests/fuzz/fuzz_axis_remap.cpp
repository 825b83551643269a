// libFuzzer target: the axis-remap spec parser ("x,y,z", "-y,x,z"; user text from the rig
// config). Any bytes give a remap or std::invalid_argument with a message; a parsed remap is a
// right-handed signed permutation: it keeps lengths and handedness and its quaternion is unit.
#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string_view>

#include "mocap/drivers/axis_remap.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  mocap::AxisRemap r;
  try {
    r = mocap::AxisRemap::parse(text);
  } catch (const std::invalid_argument& e) {
    if (std::string_view(e.what()).empty()) std::abort();
    return 0;
  }
  const Eigen::Vector3d x = r.apply(Eigen::Vector3d::UnitX());
  const Eigen::Vector3d y = r.apply(Eigen::Vector3d::UnitY());
  const Eigen::Vector3d z = r.apply(Eigen::Vector3d::UnitZ());
  if (std::abs(x.norm() - 1) > 1e-12 || std::abs(y.norm() - 1) > 1e-12) std::abort();
  if (std::abs(x.cross(y).dot(z) - 1) > 1e-12) std::abort();  // right-handed
  const Eigen::Quaterniond q = r.apply(Eigen::Quaterniond::Identity());
  if (std::abs(q.norm() - 1) > 1e-9) std::abort();
  return 0;
}
