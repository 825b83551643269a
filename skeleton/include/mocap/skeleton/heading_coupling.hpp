// Kinematic heading coupling at the hinges (knees, elbows): a slowly varying heading (earth-z)
// correction of each hinge child's sensor relative to its parent, from the hinge constraint.
//
// Why: every sensor's filter takes its heading from its own magnetometer; hard-iron residuals,
// scale errors and local disturbances turn each sensor's heading by a different, slowly varying
// amount (2-3 deg as a sensor turns in a clean field, tens of degrees beside a magnet), which no
// calibration can absorb. A hinge joint lets the body itself measure the difference: the flexion
// axis of the parent and of the child is the same line in the earth frame (q_earth_parent * y ==
// q_earth_child * y), so the azimuth difference of the two axes is the heading offset between the
// two sensors' earth frames (Laidig et al. 2017, magnetometer-free heading for hinge joints;
// Xsens's kinematic coupling). Each hinge's offset estimate follows the measured one with time
// constant tau_s, only while it is observable:
//  - the joint is flexed by >= min_flex_deg: near full extension a heading offset of the child
//    and a twist of its mounting about the (then common) long axis look the same, and the
//    mounting belongs to the calibration (HingeAxisRefiner);
//  - both axes are at least min_axis_horizontal out of vertical (azimuth defined);
//  - both axes have the same elevation within max_elevation_mismatch (the pair behaves as a
//    hinge: a filter tilt error or a non-hinge motion is not read as heading).
// The offset estimate is capped at +-max_correction_deg, so a wrong constraint (e.g. a sensor
// moved on its segment) cannot turn a segment further; each step is limited to
// max_residual_deg of the measured offset. Which of the two sensors drifted is not observable
// at the hinge. The parent (thigh, upper arm: the side of the pelvis/torso reference chain) is
// the reference and the child is turned onto it; the child's correction is carried to the
// segment beyond it (foot, hand), so the 3-DOF joints on either side (hip/shoulder, ankle/wrist)
// keep exactly what the filters measured (while no flag is up the coupling changes no 3-DOF
// joint). Only while the parent's filter flags its magnetometer disturbed and the child's does
// not is the parent turned instead (its share ramps with the trust difference; trust drops to
// disturbed_weight while flagged, smoothed with trust_tau_s, so corrections never jump). A filter's
// heading ahead of its first reference field is flagged separately (no_reference) and not treated
// as disturbed.
//
// One estimator with the calibration: the coupling's offset is a heading offset between two
// sensors' filters *given* the mountings; the hinge refinement (HingeAxisRefiner) estimates the
// constant mounting yaws. An offset learnt under an earlier calibration (the N-pose's, before the
// refinement identified the hinge) would keep part of the mounting error the refinement has since
// removed, so both would absorb the same constant. Each hinge therefore keeps its recent
// candidate frames (joint flexed by >= candidate_flex_fraction * min_flex_deg; the last
// history_samples of them); when the calibration changes, rebase() maps them into the new
// calibration and re-runs the estimate over them from the state before the oldest kept frame,
// so the offset is always the one the current calibration would have produced (up to the
// exp(-window / tau_s) weight of the frames dropped from the window).
//
// Pure, deterministic; one instance per skeleton, reset with the calibration. The history is
// allocated once at construction; update() and rebase() do not allocate.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <vector>

#include "mocap/core/segments.hpp"
#include "mocap/skeleton/calibration.hpp"
#include "mocap/skeleton/rig.hpp"

namespace mocap {

struct HeadingCouplingOptions {
  bool enabled = false;
  double tau_s = 1.0;                   ///< time constant, counted over observable time
  double min_flex_deg = 20;             ///< joint rotation below this: not observable
  double min_axis_horizontal = 0.5;     ///< |horizontal part| of both unit axes at least this
  double max_elevation_mismatch = 0.1;  ///< |a_parent.z - a_child.z| at most this
  double max_correction_deg = 25;       ///< cap of each hinge's offset estimate
  double max_residual_deg = 20;         ///< a measured offset is clamped to this per step
  double max_step_s = 0.1;              ///< longer gaps between updates count as this
  double disturbed_weight = 0.05;       ///< trust of a sensor flagged disturbed (clean: 1)
  double trust_tau_s = 1.0;             ///< time constant of the trust after a flag change
  /// The child's correction also turns the segment beyond it (foot, hand), so the 3-DOF ankle
  /// and wrist keep what the filters measured.
  bool carry_distal = true;
  /// Candidate frames kept per hinge for rebase() (0: no history, an offset keeps what it learnt
  /// under earlier calibrations). 2048 at 100 Hz is ~20 tau_s of flexed time.
  int history_samples = 2048;
  /// A frame is kept when the joint angle is at least this fraction of min_flex_deg (a
  /// calibration change moves the angle by a few degrees; the replay applies the exact gate).
  double candidate_flex_fraction = 0.5;
};

/// One hinge's state (diagnostics, tests).
struct CouplingHinge {
  double offset_deg = 0;         ///< estimated heading offset child - parent (capped)
  double last_residual_deg = 0;  ///< newest measured offset after correction (if observed)
  double observed_s = 0;         ///< total time the offset was observable
};

/// The hinges coupled: child segment corrected towards parent segment.
struct CouplingPair {
  Segment parent, child;
};
inline constexpr std::array<CouplingPair, 4> kCouplingPairs = {{
    {Segment::thigh_l, Segment::shank_l},
    {Segment::thigh_r, Segment::shank_r},
    {Segment::upper_arm_l, Segment::forearm_l},
    {Segment::upper_arm_r, Segment::forearm_r},
}};

/// The segment beyond each coupled child (shank -> foot, forearm -> hand), else -1.
inline constexpr std::array<int8_t, kSegmentCount> kCouplingCarry = {
    -1, -1, -1, -1, -1, 6, -1, -1, 9, -1, -1, 12, -1, -1, 15, -1};
static_assert(kCouplingCarry[index(Segment::forearm_l)] == index(Segment::hand_l) &&
              kCouplingCarry[index(Segment::forearm_r)] == index(Segment::hand_r) &&
              kCouplingCarry[index(Segment::shank_l)] == index(Segment::foot_l) &&
              kCouplingCarry[index(Segment::shank_r)] == index(Segment::foot_r));

class HeadingCoupling {
 public:
  explicit HeadingCoupling(RigMapping rig, HeadingCouplingOptions options = {});

  /// Forgets every correction (new calibration).
  void reset();
  /// One frame: calibrated segment orientations without this correction (q_earth_segment),
  /// `have` the fresh ones, `mag_disturbed` each sensor's filter flag. Updates the
  /// corrections; allocation-free.
  void update(const std::array<Eigen::Quaterniond, kSegmentCount>& q_earth_segment,
              const std::array<bool, kSegmentCount>& have,
              const std::array<bool, kSegmentCount>& mag_disturbed, int64_t t_ns);
  /// Per-segment heading correction, rad (0 for segments outside the coupled hinges).
  const std::array<double, kSegmentCount>& correction_rad() const { return corr_; }
  /// The corrected orientation of `segment`: Rz(correction) * q_earth_segment.
  Eigen::Quaterniond apply(int segment, const Eigen::Quaterniond& q_earth_segment) const;
  const std::array<CouplingHinge, kCouplingPairs.size()>& hinges() const { return hinge_; }
  const HeadingCouplingOptions& options() const { return opt_; }
  /// The calibration the orientations passed to update() use changed from `from` to `to` (the
  /// hinge refinement's update): maps the kept frames into `to` and re-estimates each hinge's
  /// offset over them (see the top of this file). Allocation-free.
  void rebase(const Calibration& from, const Calibration& to);

 private:
  struct Frame {
    Eigen::Quaterniond q_parent, q_child;  ///< calibrated orientations (current calibration)
    double dt_s;
  };
  /// One step of the offset estimate (offset_rad, state st) from one frame; true if observable.
  bool step(const Eigen::Quaterniond& q_parent, const Eigen::Quaterniond& q_child, double dt_s,
            double& offset_rad, CouplingHinge& st) const;
  void push(size_t hinge, const Frame& f);

  RigMapping rig_;
  HeadingCouplingOptions opt_;
  std::vector<Frame> hist_;                                  ///< per hinge: a ring of capacity
  std::array<size_t, kCouplingPairs.size()> hist_head_{};    ///< oldest kept frame
  std::array<size_t, kCouplingPairs.size()> hist_size_{};    ///< frames kept
  std::array<CouplingHinge, kCouplingPairs.size()> base_{};  ///< state before the oldest frame
  std::array<double, kSegmentCount> corr_{};
  std::array<double, kSegmentCount> trust_{};
  std::array<CouplingHinge, kCouplingPairs.size()> hinge_{};
  std::array<int64_t, kCouplingPairs.size()> t_last_ns_{};
};

}  // namespace mocap
