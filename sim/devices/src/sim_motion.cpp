// Truth motions for simulated devices: static, rotate, or a CSV file (see sim_device.hpp).
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "mocap/core/units.hpp"
#include "mocap/devsim/sim_device.hpp"

namespace mocap {
namespace {

const Eigen::Vector3d kField_uT(0.0, 20.0, -40.0);  // ENU earth field: north and down

ImuSample from_orientation(const Eigen::Quaterniond& q_earth_sensor, const Eigen::Vector3d& gyr) {
  ImuSample s;
  s.q_device_sensor = q_earth_sensor;
  s.gyr_rad_s = gyr;
  s.acc_m_s2 = q_earth_sensor.conjugate() * Eigen::Vector3d(0, 0, kStandardGravity_m_s2);
  s.mag_uT = q_earth_sensor.conjugate() * kField_uT;
  s.valid = kFieldGyr | kFieldAcc | kFieldMag | kFieldQuat;
  s.flags = kFlagSynthetic;
  return s;
}

class StaticMotion final : public Motion {
 public:
  ImuSample at(int64_t t) const override {
    ImuSample s = from_orientation(Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero());
    s.t_device_ns = t;
    return s;
  }
};

/// Yaw at 90 deg/s with roll oscillating +-30 deg at 0.5 Hz: q = Rz(yaw) Rx(roll).
class RotateMotion final : public Motion {
 public:
  ImuSample at(int64_t t) const override {
    const double ts = static_cast<double>(t) * 1e-9;
    const double wz = M_PI / 2, a = M_PI / 6, f = 2 * M_PI * 0.5;
    const double yaw = wz * ts, roll = a * std::sin(f * ts), droll = a * f * std::cos(f * ts);
    const Eigen::Quaterniond q =
        Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
        Eigen::Quaterniond(Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()));
    // Body rate: omega_sensor = Rx(roll)^T * (0,0,wz) + (droll,0,0).
    const Eigen::Vector3d gyr =
        Eigen::AngleAxisd(-roll, Eigen::Vector3d::UnitX()) * Eigen::Vector3d(0, 0, wz) +
        Eigen::Vector3d(droll, 0, 0);
    ImuSample s = from_orientation(q, gyr);
    s.t_device_ns = t;
    return s;
  }
};

class CsvMotion final : public Motion {
 public:
  explicit CsvMotion(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw std::invalid_argument("motion file " + path + ": cannot open");
    std::string line;
    int lineno = 0;
    while (std::getline(in, line)) {
      ++lineno;
      if (line.empty() || line[0] == '#' || std::isalpha(static_cast<unsigned char>(line[0])))
        continue;
      std::replace(line.begin(), line.end(), ',', ' ');
      std::istringstream ss(line);
      std::vector<double> v;
      double x;
      while (ss >> x)
        v.push_back(x);
      if ((v.size() != 10 && v.size() != 14) ||
          !std::all_of(v.begin(), v.end(), [](double d) { return std::isfinite(d); }))
        throw std::invalid_argument(
            "motion file " + path + ":" + std::to_string(lineno) +
            ": expected 10 or 14 finite numbers (t_s, gyr, acc, mag[, q wxyz])");
      ImuSample s;
      s.t_device_ns = static_cast<int64_t>(v[0] * 1e9);
      s.gyr_rad_s = {v[1], v[2], v[3]};
      s.acc_m_s2 = {v[4], v[5], v[6]};
      s.mag_uT = {v[7], v[8], v[9]};
      s.valid = kFieldGyr | kFieldAcc | kFieldMag;
      if (v.size() == 14) {
        s.q_device_sensor = Eigen::Quaterniond(v[10], v[11], v[12], v[13]).normalized();
        s.valid |= kFieldQuat;
      }
      s.flags = kFlagSynthetic;
      if (!rows_.empty() && s.t_device_ns <= rows_.back().t_device_ns)
        throw std::invalid_argument("motion file " + path + ":" + std::to_string(lineno) +
                                    ": time must increase");
      rows_.push_back(s);
    }
    if (rows_.size() < 2)
      throw std::invalid_argument("motion file " + path + ": needs at least two rows");
    span_ns_ = rows_.back().t_device_ns - rows_.front().t_device_ns;
  }
  ImuSample at(int64_t t) const override {
    const int64_t rel = t % (span_ns_ + 1);
    auto it = std::upper_bound(rows_.begin(), rows_.end(), rows_.front().t_device_ns + rel,
                               [](int64_t v, const ImuSample& s) { return v < s.t_device_ns; });
    ImuSample s = *(it == rows_.begin() ? it : it - 1);
    s.t_device_ns = t;
    return s;
  }

 private:
  std::vector<ImuSample> rows_;
  int64_t span_ns_ = 0;
};

}  // namespace

std::unique_ptr<Motion> make_motion(const std::string& spec) {
  if (spec == "static") return std::make_unique<StaticMotion>();
  if (spec == "rotate") return std::make_unique<RotateMotion>();
  if (spec.size() > 4 && spec.substr(spec.size() - 4) == ".csv")
    return std::make_unique<CsvMotion>(spec);
  throw std::invalid_argument("motion \"" + spec + "\": expected static, rotate or FILE.csv");
}

}  // namespace mocap
