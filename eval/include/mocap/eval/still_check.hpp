// Inclination truth without optical truth: while a sensor is still, its accelerometer reads
// gravity alone, so the filter's "up" (earth z in the sensor frame) must point along the
// measured specific force. check_stills finds each sensor's still moments in a recording (long
// stands and the short flat-foot moments of a stance) and scores the filter's inclination
// there, at the moment's onset, before a rest could pull the inclination back: what the motion
// before it (impacts, fast turns) left behind. Used by `mocap stills` and tests/filter.
#pragma once

#include <string>
#include <vector>

#include "mocap/core/imu_sample.hpp"
#include "mocap/filter/filter_params.hpp"

namespace mocap {

struct StillCheckOptions {
  double gyr_th_rad_s = 0.5;  ///< |gyr| below this ...
  double acc_th_m_s2 = 0.5;   ///< ... and |acc| within this of the sensor's g (its first stand)
  double min_s = 0.05;        ///< for at least this long
  double onset_s = 0.5;       ///< scored over at most this much of the moment's start
  double long_s = 1.0;        ///< moments this long are stands, shorter ones stances
  bool use_mag = false;       ///< feed the magnetometer (9D) when the samples hold one
};

/// One still moment of one sensor.
struct StillMoment {
  double t_begin_s = 0, t_end_s = 0;  ///< from the sensor's first sample
  /// RMS over the scored samples of the angle between the filter's up and the measured
  /// specific force, degrees.
  double err_deg = 0;
};

struct SensorStills {
  std::vector<StillMoment> moments;  ///< after the first (the start, where the filter settles)
  double g_m_s2 = 0;                 ///< the sensor's |acc| at its first stand
  double stand_rms_deg = 0, stance_rms_deg = 0;  ///< RMS of err_deg over stands / stances
  int stands = 0, stances = 0;
  double max_deg = 0, max_t_s = 0;  ///< the worst moment
};

/// Still moments of one sensor's samples (time order; gyr and acc in every sample), the first
/// one (at the start) included.
std::vector<StillMoment> find_still_moments(const std::vector<ImuSample>& samples,
                                            const StillCheckOptions& o, double& g_m_s2);

/// Runs AttitudeFilter(params) over one sensor's samples and scores its still moments.
SensorStills check_stills(const std::vector<ImuSample>& samples, const FilterParams& params,
                          const StillCheckOptions& o);

}  // namespace mocap
