// A hinge joint's axis (a knee; an elbow where its lower sensor does not turn with pronation:
// the body tracker fits knees only) in each of its two sensors' frames, from their
// inclinations alone. Turning about the hinge does not tilt the hinge's axis, so the axis has the
// same elevation seen from either segment: (q1 j1).z = (q2 j2).z, i.e. u1.j1 = u2.j2 with u the
// earth's up axis in each sensor's frame. No heading, magnetometer or mounting enters (a 6D
// filter's frame has any heading): it finds the axis of a sensor strapped any way, from
// ordinary motion that tilts the leg or arm (walking, running, sitting down, a squat). For a
// sagittal motion the answer is the normal of the plane the up axes sweep in each frame. The
// same constraint with the segments' angular rates (|w1 x j1| = |w2 x j2|, Seel et al. 2012)
// was tried first: on the real running recording (shared/datasets/qmt-fullbody) the thigh's
// soft tissue twists it at every foot strike at over 10 rad/s and the rate fit found the
// femur's long axis; inclinations barely see that twist.
//
// The constraint's normal matrix, sum of v v^T with v = [u1; -u2] (6x6), is kept with
// forgetting (kForgetS). Once an answer from full evidence has fixed the axes' relative sign, the
// whole hinge constraint joins it: q1 j1 = Rz(d) q2 j2, whose horizontal rows need d, the two 6D
// frames' relative heading. d drifts, so it is taken per kWindowS window and fitted afresh to the
// axes at every solve: each window keeps its rows in a form any d can be put into (Window), so the
// fit alternates between the axes and the windows' headings, a least-squares fit of both over
// the last kForgetS. (Following d with the axes as they were and adding rows with it, as
// before, made rows agree with whatever axes the fit had: in a long stand the left knee's
// axes walked 20-25 deg off; the real knees 10.4 / 11.9 deg -> 9.9 / 11.6.) On the real run
// the elevation alone leaves the axes 4-8 deg from the best hindsight fit after 100 s and
// 20-40 deg off in the first minute, the knees held to them 15.5 / 17.2 deg off their hinge
// (scripts/qmt-knees). The least eigenvector, each half normalised, is the pair of axes. The
// gap to the next eigenvalue gives the one-sigma (a motion that tilts both segments the same
// way all the time leaves two near-equal ones: no answer). The relative sign is judged from
// the elevation rows alone (the horizontal ones were taken with the d of the sign at the time
// and would keep a wrong one).
//
// The pose prior. In the N-pose both segments hang vertical and the hinge is straight, so its
// axis is horizontal there (a real knee's within a few degrees): u1.j1 = 0 and u2.j2 = 0 with
// the capture's up axes, added to every solve with the weight of kPriorSamples samples. The
// elevation rows alone leave one direction nearly open while the two segments tilt together
// with little flexion (tilting both axes towards their up axes by the same angle keeps
// u1.j1 = u2.j2): on the real run the first answer's axes were 30-35 deg above the horizontal
// or 5-7 below depending on the moment of the calibration (1.5 or 2 s into the still start),
// and 120 s of forgetting kept that for a minute; the real knees scored 8.8-11.5 / 10.0-10.8
// deg over calibrations at 1-3.5 s. With the prior 8.7-9.2 / 9.4-10.6 (10-1000 samples all
// alike; CMU 6D unchanged).
//
// Signs. The fit leaves the axes' signs open (both flipped together fit as well, and one
// flipped alone does too while the axis stays level). The rates integrated since the
// calibration pose (straight knee and elbow) give the joint angle for any pair of signs,
// theta = I2.j2 - I1.j1; a real knee flexes one way from straight (an elbow the other), so the
// pair whose angle stays within [-kOvershootDeg, kMaxFlexDeg] on the flexing side in most
// recent samples points both axes to the left of the body (the segment frame's +y). add()
// never allocates: the ring of integrals is sized at construction.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

namespace mocap::rig {

class HingeAxisEstimator {
 public:
  /// Solved this often: the first answer comes within this of enough evidence (the real run's
  /// lab straps put the site prior's facings 37-68 deg off until it comes).
  static constexpr double kSolveEveryS = 0.25;
  /// Rounds of the axes / relative headings alternation per solve (one round per solve left the
  /// axes near a first rough answer for seconds: 20 deg off at 5 s in the pose prior's test).
  /// The real run's knees (scripts/qmt-knees, with the hold's fast start): solved each 1 s, one
  /// round 9.1 / 9.3 deg; each 0.25 s, one round 8.7 / 9.1, five rounds 8.6 / 9.0. kFitRounds
  /// 6x6 eigensolves per knee each solve.
  static constexpr int kFitRounds = 5;
  static constexpr double kSampleEveryS = 0.02;  ///< at most one sample per this
  static constexpr double kForgetS = 120.0;
  /// The two frames' relative heading is taken as constant over a window this long.
  static constexpr double kWindowS = 5.0;
  /// An answer from this much tilt evidence (sum of |u - u_mean|^2 over samples) is from full
  /// evidence (full_evidence()): the tracker takes it for any segment.
  static constexpr double kMinEvidence = 20.0;
  /// The first answers come from this much, marked as not from full evidence: the tracker gives
  /// one only to a segment with no facing at all, or whose assumed facing (a site normal) it
  /// contradicts by more than three combined sigmas (facing.hpp: contradicts), and only while
  /// steady (BodyTracker::apply_hinge_axes). Taken for every segment, an answer from less
  /// evidence is worse than a site prior (CMU 6D after an N-pose alone: 1.22 -> 1.26-1.30 x),
  /// but a strap far from where it was assumed, or none, is worse still (the real run: its lab
  /// straps put the site prior's facings 37-68 deg off, every sensor turned at random its knees
  /// 20-30 deg off their hinge, until the first answer).
  static constexpr double kEarlyEvidence = 5.0;
  /// The pose prior's weight, in samples (2 s of motion's rows).
  static constexpr double kPriorSamples = 100.0;
  static constexpr double kOvershootDeg = 15.0;
  static constexpr double kMaxFlexDeg = 165.0;

  /// flex_sign: +1 a knee (flexion positive about the left axis), -1 an elbow.
  explicit HingeAxisEstimator(int flex_sign = 1, int capacity = 1000);

  /// Starts over from a calibration pose (the joint straight at t_ns); 0: stops. Answers wait
  /// for kEarlyEvidence again.
  void reset(int64_t t_ns);
  /// The newest answer had kMinEvidence (an early one did not).
  bool full_evidence() const { return full_evidence_; }
  /// After reset: the pose had both segments vertical, their up axes up1, up2 (unit, each
  /// sensor's frame): the axis was horizontal in it (the pose prior above).
  void set_pose_up(const Eigen::Vector3d& up1, const Eigen::Vector3d& up2);
  /// The upper (1) and lower (2) segments' sensors: orientation (any heading frame) and
  /// bias-free rate (own frame), at sample time t_ns.
  void add(const Eigen::Quaterniond& q1, const Eigen::Quaterniond& q2,
           const Eigen::Vector3d& w1_rad_s, const Eigen::Vector3d& w2_rad_s, int64_t t_ns);
  /// A new estimate since the last call (solved and signed).
  bool updated();

  bool known() const { return known_; }
  /// The axis in each sensor's frame, pointing to the body's left (unit).
  const Eigen::Vector3d& axis1() const { return j1_; }
  const Eigen::Vector3d& axis2() const { return j2_; }
  /// One-sigma of the axes' directions, degrees.
  double sigma_deg() const { return sigma_deg_; }
  /// Share of recent samples whose angle was on the flexing side (how sure the signs are).
  double sign_agreement() const { return sign_agreement_; }
  /// That share less the next best pair of signs' (how clearly the signs were chosen: early,
  /// with little flexion, several pairs stay on the flexing side).
  double sign_margin() const { return sign_margin_; }
  /// The signs are sure enough to take the axes: the agreement and the margin over these. An
  /// early solve from little flexion had its thigh's sign the wrong way with a margin of 0.11
  /// (CMU 03_03 after an N-pose alone: the thigh 180 deg off), the right ones 0.75-0.89 (the
  /// same clip later, the real qmt run). The horizontal rows join the fit from then on.
  static constexpr double kSureSignAgreement = 0.8;
  static constexpr double kSureSignMargin = 0.5;
  bool signs_sure() const {
    return sign_agreement_ >= kSureSignAgreement && sign_margin_ >= kSureSignMargin;
  }
  /// The two sensors' frames' relative heading, rad: q1 axis1 = Rz(this) q2 axis2 (once known).
  double relative_heading_rad() const { return d_rad_; }

 private:
  struct Entry {
    Eigen::Vector3d i1, i2;  ///< rates integrated since reset
  };
  void solve();
  /// The horizontal rows of every window, each with the relative heading that fits the axes
  /// as they are (d_rad_ set to the newest window's).
  Eigen::Matrix<double, 6, 6> horizontal_rows();
  void choose_signs(bool relative_sign_known);

  int flex_sign_;
  std::vector<Entry> ring_;
  int head_ = 0, count_ = 0;
  int64_t t0_ns_ = 0, t_prev_ns_ = 0, t_entry_ns_ = 0, t_solve_ns_ = 0;
  Eigen::Vector3d i1_ = Eigen::Vector3d::Zero(), i2_ = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 6, 6> normal_ = Eigen::Matrix<double, 6, 6>::Zero();
  /// The pose prior's rows (zero without one).
  Eigen::Matrix<double, 6, 6> prior_ = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> sum_ = Eigen::Matrix<double, 6, 1>::Zero();
  /// The horizontal rows of one kWindowS window, kept so that any relative heading d can be
  /// put in at a solve: with r the rows x, y of each sample's rotation matrix (R1, R2),
  /// a = sum r1 r1^T, b = sum r2 r2^T, cc = sum r1_x r2_x^T + r1_y r2_y^T,
  /// cs = sum r1_y r2_x^T - r1_x r2_y^T; the rows of q1 j1 = Rz(d) q2 j2 then sum to
  /// [[a, -m], [-m^T, b]] with m = cos(d) cc + sin(d) cs, and the d that fits axes j1, j2 best
  /// is atan2(j1^T cs j2, j1^T cc j2).
  struct Window {
    Eigen::Matrix3d a = Eigen::Matrix3d::Zero(), b = Eigen::Matrix3d::Zero(),
                    cc = Eigen::Matrix3d::Zero(), cs = Eigen::Matrix3d::Zero();
    int n = 0;
  };
  /// The last kForgetS of windows, a ring; the newest is being filled.
  std::vector<Window> windows_;
  int window_head_ = 0;
  int64_t t_window_ns_ = 0;
  double d_rad_ = 0;
  bool relative_sign_known_ = false;
  double weight_ = 0;
  bool known_ = false, updated_ = false;
  /// An answer from full evidence had sure signs since the reset: the horizontal rows join (not
  /// from an early answer: fitted to it, they would hold the axes near a rough first answer).
  bool rows_on_ = false;
  Eigen::Vector3d j1_ = Eigen::Vector3d::UnitY(), j2_ = Eigen::Vector3d::UnitY();
  double sigma_deg_ = 180, sign_agreement_ = 0, sign_margin_ = 0;
  bool full_evidence_ = false;
};

}  // namespace mocap::rig
