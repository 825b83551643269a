// Functional refinement of the sensor-to-segment calibration from hinge-joint motion (knees,
// elbows): the joint-axis identification of Seel et al. (2014) restricted to the one degree of
// freedom a still N/T-pose leaves open.
//
// A still pose fixes each sensor's mounting up to a rotation about the vertical: the calibration
// has to assume every sensor's heading agrees with the body heading. When it does not (the
// heading source is off, e.g. the pelvis sensor's mount is turned by 5 deg, or a filter's
// heading is off by a hard-iron residual), a calibrated segment frame is yawed by alpha against
// the true one: q_earth_segment_est = Rz(eps) q_earth_segment Rz(-alpha), and every joint axis
// is turned by the difference (a knee flexing by 100 deg shows ~alpha * 1.7 deg of false
// ab/adduction). For a hinge, the angular rates of both segments satisfy
// |w_parent x j_parent| = |w_child x j_child| (the rates off the axis are the same vector),
// with j = the flexion axis in each segment frame; rates are taken in the calibrated segment
// frames, which makes them independent of the earth heading. With j = Rz(phi) x in the
// horizontal plane of the segment frame, |w x j|^2 is linear in (cos 2phi, sin 2phi), so the
// squared residuals reduce to running sums (a 4x4 quadratic form per hinge, no buffers), and the
// two yaw offsets are found by a search over +-max_yaw_deg. That residual vanishes to fourth
// order when a segment turns about the axis itself (|w x j|^2 ~ |w|^2 d^2 for an axis error d,
// squared again in the cost): an upper arm still while the elbow curls leaves the forearm's yaw
// on a flat cost that small rate inconsistencies elsewhere (rigid arm raises: filter tilt
// corrections, sample timing) move by degrees. So where one segment is nearly still, the
// direction of the relative rate, which is the axis in the other segment's frame, adds the
// first-order term |w_rel|^2 |w_rel x j|^2 (also linear in cos 2phi, sin 2phi: the same sums).
// The sums are built in blocks, each weighted by the inverse of its own mean squared residual at
// its own best yaws (HingeRefineOptions::noise_weighting): motion whose rates fit a rigid hinge
// badly (a turn on the spot) does not outweigh clean flexion.
// Corrected calibration: q_sensor_segment <- q_sensor_segment Rz(alpha), q_correction <- Rz(-alpha)
// q_correction, so that every refined segment reads Rz(e) q_earth_segment with one common heading
// error e, which cancels in all joint rotations. Segments without an identified hinge get the mean
// offset. The mean offset is also -e (the N-pose made eps_i - alpha_i = e for every sensor, and the
// filters' magnetometer heading errors eps_i scatter around zero), so every segment is turned by
// it: this corrects the body heading (walking direction) too.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>

#include "mocap/core/segments.hpp"
#include "mocap/skeleton/calibration.hpp"
#include "mocap/skeleton/rig.hpp"

namespace mocap {

struct HingeRefineOptions {
  bool enabled = true;
  /// A hinge's estimate is used once the joint has flexed this much in total (sum of |rate| dt
  /// of the relative rotation): ~1.5 walking strides, one deep knee bend, one elbow curl.
  double min_travel_deg = 150;
  double max_yaw_deg = 40;         ///< search range of each segment's yaw offset
  double update_interval_s = 0.5;  ///< re-estimation period
  double max_step_s = 0.1;     ///< increments over longer gaps (and rates older than this) unused
  double min_rate_deg_s = 10;  ///< increments with both segments slower than this are skipped
  /// A via pair's sample counts while the joint before its child moves slower than this
  /// fraction of the hinge's relative rate plus min_rate_deg_s / 2.
  double via_still_fraction = 0.25;
  /// Direction terms: the hinge's relative rate is along the axis in both segment frames, a
  /// first-order constraint where the rate-norm residual is only fourth-order (a segment turning
  /// about the axis itself: an upper arm still while the elbow curls, a sagittal knee bend).
  /// Converting it into one frame mixes in the other segment's rate through the two filters'
  /// heading difference, so each frame's term is taken only while the other segment's rate is
  /// at most this fraction of the relative rate. 0 = rate norms only (Seel et al.).
  double direction_fraction = 0.3;
  /// The parent's yaw is used only if the parent itself turned this much about axes other than
  /// the hinge axis (rotation about the axis alone, or none, leaves its yaw open).
  double min_parent_off_axis_deg = 0;
  /// Ambiguous minima: a fit's cost often has a second minimum degrees away in the child's yaw
  /// whose cost is within a fraction of a percent of the best. Every minimum whose cost is within
  /// this fraction of the lowest counts as a candidate, and the candidate nearest the yaw offsets
  /// in use (0 = the N-pose calibration until one is applied) is kept; the offset moves
  /// to another basin only once that basin's cost is lower by more than this fraction (a
  /// hysteresis: the data must clearly favour it). 0 = always the lowest minimum; negative = the
  /// basin of the search grid's lowest node (the former search, which depends on the grid).
  /// Default: the former search (-1); 0.02 wins the ambiguous arm raise cell but loses two other
  /// targets on the accuracy grid (docs/accuracy.md, "Ambiguous minima"), so it is opt-in.
  double basin_margin = -1;
  /// Noise weighting: the residuals are summed in blocks (one per update_interval_s, extended
  /// until it holds block_min_samples), and each block enters the fit with the inverse of its own
  /// mean squared residual at its own best yaws (weighted least squares with the noise level
  /// estimated per block). Motion whose rates are inconsistent with a rigid hinge by more than
  /// the filters' usual error (a turn on the spot: heading corrections of the magnetometer and
  /// gyro scale errors on the large common rate about the vertical, rates of the two segments
  /// from different instants at high angular acceleration) then no longer outweighs clean
  /// flexion; measured in docs/skeleton.md. false = every residual weighs the same (the former
  /// fit).
  bool noise_weighting = true;
  int block_min_samples = 20;
  /// Floor of a block's mean squared residual relative to its mean squared rate scale
  /// ((|w_p|^2 + |w_c|^2)^2): a block that fits almost exactly (ideal sensors) is not given an
  /// unbounded weight. 1e-9 ~ a relative rate inconsistency of 3e-5.
  double block_noise_floor = 1e-9;
};

/// One hinge's identification state (for diagnostics and the daemon's status).
struct HingeEstimate {
  bool valid = false;         ///< travel reached and the fit is well-conditioned
  double travel_deg = 0;      ///< accumulated flexion travel
  double parent_yaw_deg = 0;  ///< estimated yaw offset of the parent's calibrated frame
  double child_yaw_deg = 0;   ///< ... and of the child's (joint fit of both)
  /// The child's yaw offset in use: the joint fit's, or, when the parent's yaw is not pinned
  /// (parent_valid false, via pairs), the best fit given the parent's applied (mean) offset.
  double applied_child_yaw_deg = 0;
  double rms_residual = 0;       ///< RMS of |w_p x j_p|^2 - |w_c x j_c|^2 relative to its scale
  double parent_travel_deg = 0;  ///< the parent's own rotation off the hinge axis meanwhile
  bool parent_valid = false;     ///< the parent turned enough to pin its yaw too
};

/// A segment pair moving about one hinge: knees (thigh-shank) and elbows (upper arm-forearm),
/// flexion about y. With `via` set, the child is the segment beyond the hinge's child (the hand
/// beyond the forearm) and a sample counts only while the joint between them (the wrist) is
/// still, so the elbow's flexion identifies the hand's mounting yaw too; only the child's
/// estimate is used from such a pair.
struct RefinePair {
  Segment parent, child;
  int via = -1;  ///< segment index between the hinge and `child`, or -1
};
inline constexpr std::array<RefinePair, 6> kRefinePairs = {{
    {Segment::thigh_l, Segment::shank_l},
    {Segment::thigh_r, Segment::shank_r},
    {Segment::upper_arm_l, Segment::forearm_l},
    {Segment::upper_arm_r, Segment::forearm_r},
    {Segment::upper_arm_l, Segment::hand_l, index(Segment::forearm_l)},
    {Segment::upper_arm_r, Segment::hand_r, index(Segment::forearm_r)},
}};
/// The pairs that are hinges of their own (no via): the first four.
inline constexpr size_t kRefineHingeCount = 4;

class HingeAxisRefiner {
 public:
  explicit HingeAxisRefiner(RigMapping rig, HingeRefineOptions options = {});

  /// Forgets everything (new base calibration).
  void reset();
  /// The newest segment orientations under the base calibration (the one being refined) and
  /// their sample times; `have` says which are valid. Rates come from each segment's own
  /// consecutive samples (frames may hold 0 or 2 new samples of a sensor). Allocation-free.
  void add(const std::array<Eigen::Quaterniond, kSegmentCount>& q_earth_segment_base,
           const std::array<int64_t, kSegmentCount>& t_sample_ns,
           const std::array<bool, kSegmentCount>& have, int64_t t_ns);
  /// Re-estimates when update_interval_s has passed since the last estimate; returns true when
  /// the yaw offsets changed (then apply() them to the base calibration).
  bool update(int64_t t_ns);

  /// Per-segment yaw offset of the base calibration's segment frame (rad; 0 until known).
  const std::array<double, kSegmentCount>& yaw_offset_rad() const { return alpha_; }
  const std::array<HingeEstimate, kRefinePairs.size()>& hinges() const { return est_; }
  /// Number of hinges (knees, elbows; not the via pairs) with a valid estimate.
  int valid_hinges() const;
  const HingeRefineOptions& options() const { return opt_; }

  /// Mean yaw offset of the identified segments (rad): minus the base calibration's body-heading
  /// error, since the filters' magnetometer headings scatter around the truth.
  double common_yaw_rad() const { return common_; }

  /// One local minimum of a pair's cost (yaws in rad).
  struct YawFit {
    double yaw_p = 0, yaw_c = 0, cost = 0;
  };
  /// Fits the two yaw offsets of one pair to the cost x^T h x + 2 g^T x + s, x = (cos fp, sin
  /// fp, cos fc, sin fc), f = 2 (90 deg + yaw) (the squared hinge residuals; `h` symmetric):
  /// every local minimum of a 1 deg grid over +-range is taken to its exact minimum by damped
  /// Newton iterations; of the minima within `basin_margin` (relative) of the lowest cost, the
  /// one nearest the yaws in use (ref_yaw_p, ref_yaw_c) wins. With parent_fixed, the parent's yaw
  /// is `fixed_yaw_p` and only the child's is searched. Allocation-free.
  static YawFit fit(const Eigen::Matrix4d& h, const Eigen::Vector4d& g, double s, double range,
                    bool parent_fixed, double fixed_yaw_p, double ref_yaw_p, double ref_yaw_c,
                    double basin_margin);

  /// The base calibration with the yaw offsets removed and the body heading corrected by
  /// `common_rad` (segments not calibrated are left alone).
  static Calibration apply(const Calibration& base,
                           const std::array<double, kSegmentCount>& yaw_offset_rad,
                           double common_rad);

 private:
  /// The quadratic form of a pair's squared residuals (weighted sums in sums_, the open
  /// block's unweighted ones in block_).
  struct Quad {
    Eigen::Matrix4d h = Eigen::Matrix4d::Zero();  ///< sum a a^T
    Eigen::Vector4d g = Eigen::Vector4d::Zero();  ///< sum a b
    double s = 0;                                 ///< sum b^2
    double scale = 0;                             ///< sum of (|w_p|^2 + |w_c|^2)^2
    int n = 0;                                    ///< samples
  };
  struct Sums : Quad {
    double travel_rad = 0;
    double parent_travel_rad = 0;  ///< the parent's own rotation over the same samples
  };
  /// Folds pair h's open block into its sums with the block's noise weight (noise_weighting) or
  /// weight 1, and empties it.
  void close_block(size_t h);
  /// Fits pair `hinge` with the applied yaws (rad) as the basin reference.
  bool estimate(int hinge, double ref_yaw_p, double ref_yaw_c, double margin,
                HingeEstimate& out) const;

  RigMapping rig_;
  HingeRefineOptions opt_;
  std::array<Sums, kRefinePairs.size()> sums_{};
  std::array<Quad, kRefinePairs.size()> block_{};
  std::array<HingeEstimate, kRefinePairs.size()> est_{};
  std::array<int, kRefinePairs.size()> n_estimated_{};  ///< sums_[h].n at the last estimate
  std::array<bool, kRefinePairs.size()> applied_{};     ///< the pair's offsets are in use
  std::array<Eigen::Quaterniond, kSegmentCount> q_prev_;
  std::array<int64_t, kSegmentCount> t_prev_ns_{};
  std::array<bool, kSegmentCount> have_prev_{};
  std::array<Eigen::Vector3d, kSegmentCount> w_;  ///< newest rate, segment frame, rad/s
  std::array<int64_t, kSegmentCount> t_w_ns_{};   ///< its time (0 = none)
  std::array<double, kSegmentCount> dt_w_s_{};    ///< and the span it was taken over
  int64_t t_last_update_ns_ = 0;
  bool started_ = false;
  std::array<double, kSegmentCount> alpha_{};
  double common_ = 0;
};

}  // namespace mocap
