// Parsing of axis remap strings like "-y,x,z" (see axis_remap.hpp).
#include "mocap/drivers/axis_remap.hpp"

#include <Eigen/Dense>
#include <stdexcept>
#include <string>

namespace mocap {

AxisRemap AxisRemap::parse(std::string_view text) {
  AxisRemap r;
  int n = 0;
  bool used[3] = {false, false, false};
  size_t pos = 0;
  while (pos <= text.size()) {
    size_t comma = text.find(',', pos);
    if (comma == std::string_view::npos) comma = text.size();
    std::string_view tok = text.substr(pos, comma - pos);
    while (!tok.empty() && tok.front() == ' ')
      tok.remove_prefix(1);
    while (!tok.empty() && tok.back() == ' ')
      tok.remove_suffix(1);
    double sign = 1;
    if (!tok.empty() && (tok.front() == '-' || tok.front() == '+')) {
      sign = tok.front() == '-' ? -1 : 1;
      tok.remove_prefix(1);
    }
    if (tok.size() != 1 || tok[0] < 'x' || tok[0] > 'z' || n >= 3)
      throw std::invalid_argument("axis_remap \"" + std::string(text) +
                                  "\": expected three axes like \"x,y,z\" or \"-y,x,z\"");
    const int idx = tok[0] - 'x';
    if (used[idx])
      throw std::invalid_argument("axis_remap \"" + std::string(text) + "\": axis " +
                                  std::string(tok) + " used twice");
    used[idx] = true;
    r.idx_[n] = idx;
    r.sign_[n] = sign;
    ++n;
    pos = comma + 1;
  }
  if (n != 3)
    throw std::invalid_argument("axis_remap \"" + std::string(text) + "\": needs three axes");
  Eigen::Matrix3d m_sensor_device = Eigen::Matrix3d::Zero();
  for (int i = 0; i < 3; ++i)
    m_sensor_device(i, r.idx_[i]) = r.sign_[i];
  if (m_sensor_device.determinant() < 0)
    throw std::invalid_argument("axis_remap \"" + std::string(text) +
                                "\" is a reflection (left-handed); flip one more sign");
  r.q_device_sensor_ = Eigen::Quaterniond(Eigen::Matrix3d(m_sensor_device.transpose()));
  r.identity_ = m_sensor_device.isIdentity();
  return r;
}

}  // namespace mocap
