// Gyro scale calibration from whole turns on a table (see gyro_scale.hpp).
#include "mocap/filter/gyro_scale.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

#include "mocap/core/units.hpp"

namespace mocap {

namespace {

struct Rest {
  size_t begin = 0, end = 0;  ///< sample index range [begin, end) of the averaged middle half
  Eigen::Vector3d gyr = Eigen::Vector3d::Zero(), acc = Eigen::Vector3d::Zero(),
                  mag = Eigen::Vector3d::Zero();
  bool have_acc = false, have_mag = false;
};

/// Signed angle (rad) that turns a's component perpendicular to `axis` onto b's, about `axis`.
double angle_about(const Eigen::Vector3d& axis, const Eigen::Vector3d& a,
                   const Eigen::Vector3d& b) {
  const Eigen::Vector3d pa = a - a.dot(axis) * axis, pb = b - b.dot(axis) * axis;
  return std::atan2(axis.dot(pa.cross(pb)), pa.dot(pb));
}

}  // namespace

GyroScaleResult estimate_gyro_scale(std::span<const ImuSample> s, const GyroScaleOptions& o) {
  GyroScaleResult r;
  // 1. Rests: runs of still gyro samples at least min_rest_s long, with their means.
  std::vector<Rest> rests;
  const double still = o.still_deg_s * kRadPerDeg;
  size_t i = 0;
  while (i < s.size()) {
    if (!s[i].has(kFieldGyr) || s[i].gyr_rad_s.norm() >= still) {
      ++i;
      continue;
    }
    size_t j = i;
    while (j < s.size() && (!s[j].has(kFieldGyr) || s[j].gyr_rad_s.norm() < still))
      ++j;
    if ((s[j - 1].t_host_ns - s[i].t_host_ns) * 1e-9 >= o.min_rest_s) {
      // Means over the middle half: the edges hold the slow start and end of the motions.
      Rest rest{i + (j - i) / 4, j - (j - i) / 4};
      int ng = 0, na = 0, nm = 0;
      for (size_t k = rest.begin; k < rest.end; ++k) {
        if (s[k].has(kFieldGyr)) rest.gyr += s[k].gyr_rad_s, ++ng;
        if (s[k].has(kFieldAcc)) rest.acc += s[k].acc_m_s2, ++na;
        if (s[k].has(kFieldMag)) rest.mag += s[k].mag_uT, ++nm;
      }
      rest.gyr /= std::max(ng, 1);
      rest.have_acc = na > 0;
      rest.have_mag = nm > 0;
      if (na) rest.acc /= na;
      if (nm) rest.mag /= nm;
      rests.push_back(rest);
    }
    i = j;
  }
  r.rests = static_cast<int>(rests.size());
  // 2. Each motion between two rests: a spin about one sensor axis, or rejected.
  for (size_t k = 0; k + 1 < rests.size(); ++k) {
    const Rest &a = rests[k], &b = rests[k + 1];
    const Eigen::Vector3d bias = 0.5 * (a.gyr + b.gyr);
    // From the middle of one rest to the middle of the next (the motion's slow start and end,
    // below the still threshold, belong to the spin).
    Eigen::Vector3d theta = Eigen::Vector3d::Zero();
    for (size_t m = (a.begin + a.end) / 2 + 1; m <= (b.begin + b.end) / 2 && m < s.size(); ++m) {
      if (!s[m].has(kFieldGyr)) continue;
      const double dt = (s[m].t_host_ns - s[m - 1].t_host_ns) * 1e-9;
      if (dt > 0 && dt < 0.5) theta += (s[m].gyr_rad_s - bias) * dt;
    }
    int ax = 0;
    theta.cwiseAbs().maxCoeff(&ax);
    const double spin = theta[ax];
    const double off = std::sqrt(theta.squaredNorm() - spin * spin);
    bool ok =
        std::abs(spin) >= o.min_turn_deg * kRadPerDeg && off <= o.max_off_axis * std::abs(spin);
    if (ok && a.have_acc && b.have_acc) {
      const double c = a.acc.normalized().dot(b.acc.normalized());
      ok = std::acos(std::clamp(c, -1.0, 1.0)) <= o.max_tilt_change_deg * kRadPerDeg;
    }
    if (!ok) {
      ++r.rejected_spins;
      continue;
    }
    // The net heading change: the field turns the other way in the sensor frame. A hard-iron
    // offset moves the circle the field draws during the spin off the axis: its centre (a
    // least-squares circle fit in the plane across the axis) is taken out first.
    const Eigen::Vector3d e = Eigen::Vector3d::Unit(ax);
    const Eigen::Vector3d eu = Eigen::Vector3d::Unit((ax + 1) % 3),
                          ev = Eigen::Vector3d::Unit((ax + 2) % 3);
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Eigen::Vector3d atb = Eigen::Vector3d::Zero();
    for (size_t m = a.end; m < b.begin; ++m) {
      if (!s[m].has(kFieldMag)) continue;
      const double x = s[m].mag_uT.dot(eu), y = s[m].mag_uT.dot(ev);
      const Eigen::Vector3d row(2 * x, 2 * y, 1);
      ata += row * row.transpose();
      atb += row * (x * x + y * y);
    }
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    if (ata(2, 2) >= 20) {
      const Eigen::Vector3d c = ata.ldlt().solve(atb);
      if (c.allFinite()) centre = c.x() * eu + c.y() * ev;
    }
    const double net =
        a.have_mag && b.have_mag ? -angle_about(e, a.mag - centre, b.mag - centre) : 0.0;
    const double turns = std::round((spin - net) / (2 * M_PI));
    const double truth = turns * 2 * M_PI + net;
    if (turns == 0 || std::abs(spin - truth) > o.max_net_turn_deg * kRadPerDeg) {
      ++r.rejected_spins;
      continue;
    }
    GyroScaleAxis& g = r.axis[ax];
    ++g.spins;
    g.measured_deg += std::abs(spin) / kRadPerDeg;
    g.true_deg += std::abs(truth) / kRadPerDeg;
    g.scale = g.measured_deg / g.true_deg;
  }
  return r;
}

}  // namespace mocap
