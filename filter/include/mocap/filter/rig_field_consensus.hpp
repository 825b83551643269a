// Rig consensus of the reference field: every sensor on one body sees the same earth field
// (norm, dip), so a sensor that took a local field (a magnet beside it at start-up) as its
// reference gets the median of the others' instead. Runs at a low rate outside the filters'
// per-sample path (RigEngine, the accuracy bench); see docs/filter.md ("Rig consensus").
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "mocap/filter/attitude_filter.hpp"

namespace mocap::filt {

struct RigFieldConsensusParams {
  double period_s = 0.5;  ///< the check runs at most this often
  /// A sensor's reference differs from the median when its norm or dip deviates by more than
  /// this fraction of the filters' own disturbance thresholds (mag_norm_th, mag_dip_th_deg).
  double threshold_scale = 1.0;
  int min_sensors = 3;  ///< consensus needs at least this many references (and a majority)
};

class RigFieldConsensus {
 public:
  /// Buffers for up to max_sensors filters (no allocation in step()).
  explicit RigFieldConsensus(std::size_t max_sensors, const RigFieldConsensusParams& p = {});

  /// At most every period_s (t_ns: the rig's newest sample time): once a majority of the
  /// filters with a magnetometer has a reference, the median norm and dip of those references
  /// are imposed (AttitudeFilter::set_reference_field) on every filter without one or whose
  /// reference differs. Returns the number of filters changed in this call.
  int step(int64_t t_ns, std::span<AttitudeFilter> filters);

  bool have_consensus() const { return have_; }
  double norm_uT() const { return norm_uT_; }
  double dip_rad() const { return dip_rad_; }
  /// Filters changed since construction (a reference imposed).
  int imposed_total() const { return imposed_total_; }

 private:
  RigFieldConsensusParams p_;
  std::vector<double> norms_, dips_;
  int64_t last_t_ns_ = 0;
  bool ran_ = false, have_ = false;
  double norm_uT_ = 0, dip_rad_ = 0;
  int imposed_total_ = 0;
};

}  // namespace mocap::filt
