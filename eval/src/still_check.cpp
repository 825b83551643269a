// Still-moment inclination check (see still_check.hpp).
#include "mocap/eval/still_check.hpp"

#include <algorithm>
#include <cmath>

#include "mocap/core/units.hpp"
#include "mocap/filter/attitude_filter.hpp"

namespace mocap {
namespace {

bool still_sample(const ImuSample& s, double g, const StillCheckOptions& o) {
  return s.gyr_rad_s.norm() < o.gyr_th_rad_s && std::abs(s.acc_m_s2.norm() - g) < o.acc_th_m_s2;
}

std::vector<std::pair<size_t, size_t>> still_runs(const std::vector<ImuSample>& s, double g,
                                                  const StillCheckOptions& o) {
  std::vector<std::pair<size_t, size_t>> runs;  // [begin, end)
  size_t b = 0;
  bool in = false;
  for (size_t i = 0; i <= s.size(); ++i) {
    const bool st = i < s.size() && still_sample(s[i], g, o);
    if (st && !in) {
      b = i;
      in = true;
    } else if (!st && in) {
      in = false;
      if ((s[i - 1].t_host_ns - s[b].t_host_ns) * 1e-9 >= o.min_s) runs.emplace_back(b, i);
    }
  }
  return runs;
}

}  // namespace

std::vector<StillMoment> find_still_moments(const std::vector<ImuSample>& s,
                                            const StillCheckOptions& o, double& g_m_s2) {
  std::vector<StillMoment> out;
  if (s.empty()) return out;
  // The sensor's g: its mean |acc| over its first stand (found with the nominal g).
  g_m_s2 = kStandardGravity_m_s2;
  StillCheckOptions wide = o;
  wide.acc_th_m_s2 = std::max(o.acc_th_m_s2, 1.0);
  for (const auto& [b, e] : still_runs(s, g_m_s2, wide)) {
    if ((s[e - 1].t_host_ns - s[b].t_host_ns) * 1e-9 < o.long_s) continue;
    double sum = 0;
    for (size_t i = b; i < e; ++i)
      sum += s[i].acc_m_s2.norm();
    g_m_s2 = sum / static_cast<double>(e - b);
    break;
  }
  const int64_t t0 = s.front().t_host_ns;
  for (const auto& [b, e] : still_runs(s, g_m_s2, o))
    out.push_back({(s[b].t_host_ns - t0) * 1e-9, (s[e - 1].t_host_ns - t0) * 1e-9, 0});
  return out;
}

SensorStills check_stills(const std::vector<ImuSample>& s, const FilterParams& params,
                          const StillCheckOptions& o) {
  SensorStills r;
  std::vector<StillMoment> m = find_still_moments(s, o, r.g_m_s2);
  if (s.empty() || m.empty()) return r;
  AttitudeFilter f(params);
  const int64_t t0 = s.front().t_host_ns;
  size_t k = 0;  // the moment being scored or next
  double sum2 = 0;
  int n = 0;
  auto close = [&] {
    if (n > 0) m[k].err_deg = std::sqrt(sum2 / n);
    sum2 = 0;
    n = 0;
    ++k;
  };
  for (const ImuSample& in : s) {
    ImuSample x = in;
    if (!o.use_mag) x.valid &= static_cast<uint8_t>(~kFieldMag);
    f.update(x);
    const double t = (x.t_host_ns - t0) * 1e-9;
    while (k < m.size() && t > m[k].t_end_s + 1e-9)
      close();
    if (k >= m.size() || t < m[k].t_begin_s - 1e-9 || t > m[k].t_begin_s + o.onset_s) continue;
    const FilterOutput out = f.output();
    const Eigen::Quaterniond q = o.use_mag ? out.q_earth_sensor : out.q_earth_sensor_6d;
    const Eigen::Vector3d up_s = q.conjugate() * Eigen::Vector3d::UnitZ();
    const double c = std::clamp(up_s.dot(x.acc_m_s2.normalized()), -1.0, 1.0);
    const double a = std::acos(c) * kDegPerRad;
    sum2 += a * a;
    ++n;
  }
  while (k < m.size())
    close();
  // The first moment at the very start is where the filter settles: not scored.
  if (m.front().t_begin_s < 1e-6) m.erase(m.begin());
  double st2 = 0, sn2 = 0;
  for (const StillMoment& x : m) {
    const bool stand = x.t_end_s - x.t_begin_s >= o.long_s;
    (stand ? st2 : sn2) += x.err_deg * x.err_deg;
    (stand ? r.stands : r.stances) += 1;
    if (x.err_deg > r.max_deg) {
      r.max_deg = x.err_deg;
      r.max_t_s = x.t_begin_s;
    }
  }
  if (r.stands) r.stand_rms_deg = std::sqrt(st2 / r.stands);
  if (r.stances) r.stance_rms_deg = std::sqrt(sn2 / r.stances);
  r.moments = std::move(m);
  return r;
}

}  // namespace mocap
