// The full-body tracking metric of ../shared/datasets/cmu/README.md ("How full-body tracking is
// scored"): per segment, the rotation since a reference instant, D(t) = q(t) q(t_ref)^-1 (earth
// frame), for the estimate and the truth; one rotation G, fitted once over all segments and
// frames, maps the truth's world onto the estimate's; the error at t is the angle of
// D_est(t) (G D_true(t) G^-1)^-1; RMS over the frames per segment, then the mean over the
// segments. Constant mounting offsets cancel; drift, heading disagreement between segments,
// clamped real poses, wrong axes and lag do not.
//
// Used by the accuracy run (the body tracker and the filters alone on the same samples) and by
// `mocap score` (pose CSVs against a truth CSV). Offline evaluation only: it keeps every frame.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <vector>

#include "mocap/core/segments.hpp"

namespace mocap::sim {

class SegmentMetric {
 public:
  using Orientations = std::array<Eigen::Quaterniond, kSegmentCount>;

  /// `scored[s]`: segment s is scored (carries a sensor).
  explicit SegmentMetric(const std::array<bool, kSegmentCount>& scored) : scored_(scored) {}

  /// One frame: estimated and true earth-frame segment orientations. The first frame added is
  /// the reference instant.
  void add(const Orientations& q_est, const Orientations& q_true);

  struct Result {
    int frames = 0;
    std::array<double, kSegmentCount> segment_rms_deg{};    ///< 0 for segments not scored
    double mean_deg = 0;                                    ///< mean over the scored segments
    Eigen::Quaterniond g = Eigen::Quaterniond::Identity();  ///< the fitted world rotation
  };
  /// Fits G and scores every frame added so far; with g_given, scores with that G instead (two
  /// estimates compared segment by segment under one world rotation).
  Result result(const Eigen::Quaterniond* g_given = nullptr) const;
  int frames() const { return static_cast<int>(est_.size()); }

 private:
  std::array<bool, kSegmentCount> scored_;
  Orientations ref_est_, ref_true_;
  std::vector<Orientations> est_, true_;  ///< D(t) per frame (already relative to t_ref)
};

}  // namespace mocap::sim
