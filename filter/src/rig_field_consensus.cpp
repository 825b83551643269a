// Rig consensus of the reference field (median norm and dip over the filters' references).
#include "mocap/filter/rig_field_consensus.hpp"

#include <algorithm>
#include <cmath>

#include "mocap/core/units.hpp"

namespace mocap::filt {
namespace {

double median(std::vector<double>& v, std::size_t n) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(n / 2);
  std::nth_element(v.begin(), mid, v.begin() + static_cast<std::ptrdiff_t>(n));
  if (n % 2) return *mid;
  const double hi = *mid;
  const double lo = *std::max_element(v.begin(), mid);
  return 0.5 * (lo + hi);
}
}  // namespace

RigFieldConsensus::RigFieldConsensus(std::size_t max_sensors, const RigFieldConsensusParams& p)
    : p_(p), norms_(max_sensors), dips_(max_sensors) {}

int RigFieldConsensus::step(int64_t t_ns, std::span<AttitudeFilter> filters) {
  if (ran_ && static_cast<double>(t_ns - last_t_ns_) * 1e-9 < p_.period_s) return 0;
  ran_ = true;
  last_t_ns_ = t_ns;
  std::size_t n_mag = 0, n_ref = 0;
  for (const AttitudeFilter& f : filters) {
    if (!f.mag_has_reference() && !f.mag_no_reference()) continue;  // no magnetometer
    ++n_mag;
    if (!f.mag_has_reference() || n_ref >= norms_.size()) continue;
    norms_[n_ref] = f.mag_reference_norm_uT();
    dips_[n_ref] = f.mag_reference_dip_rad();
    ++n_ref;
  }
  if (n_ref < static_cast<std::size_t>(std::max(p_.min_sensors, 1)) || 2 * n_ref <= n_mag) return 0;
  norm_uT_ = median(norms_, n_ref);
  dip_rad_ = median(dips_, n_ref);
  have_ = true;
  int changed = 0;
  for (AttitudeFilter& f : filters) {
    if (!f.mag_has_reference() && !f.mag_no_reference()) continue;
    const FilterParams& fp = f.params();
    const bool differs = !f.mag_has_reference() ||
                         std::abs(f.mag_reference_norm_uT() - norm_uT_) >
                             p_.threshold_scale * fp.mag_norm_th * norm_uT_ ||
                         std::abs(f.mag_reference_dip_rad() - dip_rad_) >
                             p_.threshold_scale * fp.mag_dip_th_deg * kRadPerDeg;
    if (!differs) continue;
    f.set_reference_field(norm_uT_, dip_rad_);
    ++changed;
  }
  imposed_total_ += changed;
  return changed;
}

}  // namespace mocap::filt
