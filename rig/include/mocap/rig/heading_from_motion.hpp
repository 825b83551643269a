// 6D rigs: the heading alignment of a sensor whose site normal is vertical (top of the head,
// instep) cannot be read in the N-pose, so it is found from motion. The segment and its parent
// (with an aligned sensor) share a joint, so they share its acceleration: the parent's sensor
// gives the joint centre's (its specific force plus the rotation terms out to the joint, gravity
// removed; for the head through the neck, held in its calibration pose), the segment's own
// sensor nearly the same vector (the joint's but for the rotation terms of the lever arm across
// the site normal, whose direction in the sensor frame depends on the very alignment sought).
// The yaw that maps the segment's horizontal acceleration onto the parent's is the missing
// alignment, for any joint (no axis assumed). The caller band-passes both signals alike (a
// filter commutes with the yaw; it removes each filter's slow gravity leak and the jitter above
// a few Hz); the fit is a weighted circular mean of the angle between them, each instant's
// weight saturating (a jump must not outvote seconds of walking), forgotten over tau_s so slow
// heading drift is followed, and once found (and settled: settle_evidence) the caller turns it
// no faster than a 6D heading drifts. Each reference sample is paired with the segment's signal
// at its time (sensors sample at their own instants). A reference further up (a foot under an
// untracked shank) gives angular rates instead: the horizontal rates of a foot and the thigh above
// follow each other, more loosely.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>

#include "mocap/core/segments.hpp"

namespace mocap::rig {

struct HeadingFromMotionOptions {
  double tau_s = 30.0;  ///< forgetting time of the fit, seconds of sample time
  /// Evidence before a yaw is given: the integral of the weighted |a_seg,h| |a_ref,h| dt, in the
  /// signal's units squared times seconds. An early estimate is refined afterwards, at the drift
  /// limit; waiting costs more than it saves (CMU 6D, 24 clips x 3 seeds, worst segment excess:
  /// 0.003: 14.0, 0.007-0.015: 5.4, 0.03: 6.2, 0.1: 16 deg; docs/accuracy.md).
  double min_evidence = 0.01;
  /// Product |a_seg,h| |a_ref,h| at which an instant's weight is halved, signal units squared.
  double saturation = 1.0;
  /// A reference sample is paired with the segment's signal interpolated to its time between
  /// two segment samples at most 2 max_pair_age_s apart, else with a segment sample at most
  /// this far from it, seconds.
  double max_pair_age_s = 0.02;
  /// After the first alignment the caller turns it at most this fast, deg/s: a mount is
  /// constant and a 6D heading drifts far slower, so a stretch of misleading motion (a foot
  /// on a bar, a sword swing) cannot turn a found alignment over.
  double max_drift_deg_s = 2.0;
  /// Except while a coherent fit settles (a joint's acceleration against its parent's; not the
  /// head through the held neck, not rates): a first estimate from few steps can be tens of
  /// degrees off, and at the drift limit it would take as many seconds to come back. Until the
  /// evidence reaches settle_evidence (about a second of saturated motion), and while the
  /// resultant keeps settle_coherence of it, the caller turns at settle_turn_deg_s. CMU 6D,
  /// 24 clips x 3 seeds, worst segment excess on the sites 7.7 -> 2.5 deg (docs/accuracy.md);
  /// evidence 0.3-3 and rate 10-45 deg/s give the same worst; without the coherence test the
  /// hanging forearms of an N-pose alone wander (forearm_l excess 2.6 -> 3.0 deg).
  double settle_evidence = 1.0;
  double settle_coherence = 0.7;
  double settle_turn_deg_s = 20.0;
  /// A heading lost in a dropout (BodyTracker: heading_lost_after_s) is found again by the
  /// same fit: from settle_evidence on, its estimate is applied whole at every application
  /// (no drift limit, no refusal of far turns: there is no heading to protect) until the
  /// evidence reaches found_evidence (about 10 s of saturated motion); from then on it is a
  /// found heading like any other.
  double found_evidence = 10.0;
  /// A lost heading's fit starts from the segment's rotation in the segment above as it was
  /// before the gap (BodyTracker::keep_joint_above), a prior worth this much of the
  /// resultant (not counted as evidence: settling and finding wait for motion). CMU 6D, a 3 s
  /// dropout at 4 s, 17 clips, the dropped segment's joint error after, mean / worst:
  /// torso 13.9 / 59.5 -> 7.6 / 22.0 deg, foot 25.3 / 143.0 -> 12.5 / 98.1 (the head, kept
  /// through the untracked neck, is found at once instead); 4 kept the torso better (6.8 /
  /// 16.5) and the upper arm worse (15.5 / 59.4 against 9.4 / 34.5), counted as evidence
  /// worse (the foot 13.8 / 122.5: found with the prior's share).
  double gap_prior = 2.0;
  /// Sensors aligned from a horizontal site normal in the N-pose are refined by the same fit:
  /// only when it disagrees by more than refine_dead_band_deg (the fit's own bias from the body
  /// model's joint centres) and by at most refine_max_deg in all (a strap tilted off its
  /// normal). 0 disables.
  double refine_max_deg = 10.0;
  double refine_dead_band_deg = 4.0;
  /// A segment whose facing a mounting motion or a knee's axes settled keeps its fit against
  /// the nearest known segment above, where that one is settled too (not a site prior), and the
  /// two headings follow the fit's drift, half each: only the part beyond hold_dead_band_deg
  /// (the fit's own bias), at most hold_turn_deg_s, about the vertical (a 6D heading frame
  /// drifts about the vertical; the mountings stay). 0 disables. CMU 6D with the mounting
  /// motion (`mocap bench accuracy --session`), the ideally aligned filters' ratio over a 10 min
  /// session's last minute 0.863 -> 0.504 x (sites), 0.921 -> 0.538 x (random straps); the
  /// clips once, seeds 1-3, 0.966 -> 0.947 / 0.974 -> 0.960 x, worst segment excess 3.06 /
  /// 3.09 -> 2.72 / 2.76 deg. Measured while the held segment alone turned, on the sites: rate
  /// 0.1 / 0.2 / 0.5 deg/s (dead band 4) worst 2.80 / 2.59 / 3.15 (a head); dead band 4 / 2 /
  /// 1 / 0 deg (0.2 deg/s) 0.959 / 0.948 / 0.949 / 0.958 x.
  double hold_turn_deg_s = 0.2;
  double hold_dead_band_deg = 2.0;
};

class HeadingFromMotion {
 public:
  explicit HeadingFromMotion(HeadingFromMotionOptions options = {}) : opt_(options) {}

  /// Starts over after a calibration: `reference[s]` is the segment whose signal segment s's is
  /// fitted to, -1 for segments whose heading needs nothing.
  void reset(const std::array<int, kSegmentCount>& reference);
  /// The reference's newest signal for segment s (earth frame, the reference's alignment).
  void add_reference(int segment, const Eigen::Vector3d& v_earth, int64_t t_ns);
  /// Segment s's newest signal under the alignment in use; paired with its reference's.
  void add(int segment, const Eigen::Vector3d& v_earth, int64_t t_ns);
  /// The yaw (rad, about the vertical) that would align the segment's sensor, once there is
  /// enough evidence; false before.
  bool estimate(int segment, double& yaw_rad) const;
  /// Segment s's fit has less than settle_evidence, and what it has agrees with itself (the
  /// resultant is at least settle_coherence of the evidence).
  bool settling(int segment) const;
  /// Segment s's fit's evidence (0 when it is not fitted).
  double evidence(int segment) const;
  /// The caller turned the segment's alignment by yaw_rad: the fit continues in the new frame.
  void applied(int segment, double yaw_rad);
  /// Segment s's reference's alignment turned by yaw_rad: the fit continues in its new frame.
  void reference_turned(int segment, double yaw_rad);
  /// Segment s's evidence is dropped and its fit starts over against `reference` (the
  /// reference's alignment changed, or a nearer one became known).
  void restart(int segment, int reference);
  /// After restart: a prior that the alignment as it is now is right, a resultant of `weight`
  /// at yaw 0 (evidence() unchanged).
  void seed(int segment, double weight);
  /// Segment s is no longer fitted (another source holds its heading).
  void stop(int segment) {
    if (segment >= 0 && segment < kSegmentCount) fit_[segment].ref = -1;
  }
  bool active() const { return active_; }
  int reference(int segment) const { return fit_[segment].ref; }

 private:
  /// One segment's fit against its reference.
  struct Fit {
    int ref = -1;  ///< the reference segment, -1: not fitted
    /// The reference's newest signal (horizontal), awaiting its pair while ref_pending.
    Eigen::Vector2d ref_v = Eigen::Vector2d::Zero();
    int64_t ref_t_ns = 0;
    bool ref_pending = false;
    /// The segment's two newest signals (the reference's is interpolated between them).
    Eigen::Vector2d v = Eigen::Vector2d::Zero(), prev_v = Eigen::Vector2d::Zero();
    int64_t t_ns = 0, prev_t_ns = 0;
    bool have = false, have_prev = false;
    /// Time of the last paired reference sample (the weight's dt).
    int64_t pair_t_ns = 0;
    bool have_pair = false;
    /// Weighted sum of |a||b| (cos, sin) of the angle from the signal to the reference's.
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    double evidence = 0;
  };
  void pair(Fit& f);

  HeadingFromMotionOptions opt_;
  bool active_ = false;
  std::array<Fit, kSegmentCount> fit_{};
};

}  // namespace mocap::rig
