// Regression on real straps without a magnetometer: the real 6D full-body run
// (../shared/datasets/qmt-fullbody: 16 IMUs as a lab strapped them, running and jumping)
// replayed as `mocap replay --calibrate npose@2 --set filter.use_mag=false` does, through the
// replay engine mocapd runs. A real knee stays near its hinge: each knee's rotation off its
// flexion axis (scripts/qmt-knees prints the same figure); and no segment jumps: an alignment
// found from motion turns its segment at most 360 deg/s, so no frame-to-frame turn comes near
// the 30 deg bound (the run's own fastest is 17 deg, a foot at a strike). The same with every
// sensor turned at random on its segment (strapped any way).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "mocap/core/segments.hpp"
#include "mocap/core/units.hpp"
#include "mocap/daemon/replay.hpp"
#include "mocap/daemon/replay_run.hpp"

namespace mocap::daemon {
namespace {

struct KneeFrames final : outputs::Output {
  std::vector<PoseFrame> f;
  void on_frame(const PoseFrame& frame) override { f.push_back(frame); }
};

Eigen::Quaterniond quat(const std::array<float, 4>& q) {
  return {q[0], q[1], q[2], q[3]};
}

/// The joint rotation's angle left after its twist about the upper segment's left (y) axis.
double off_hinge_deg(const Eigen::Quaterniond& q) {
  const double n = std::hypot(q.w(), q.y());
  if (n < 1e-9) return 180;
  const Eigen::Quaterniond twist(q.w() / n, 0, q.y() / n, 0);
  const Eigen::Quaterniond swing = q * twist.conjugate();
  return 2 * std::acos(std::min(1.0, std::abs(swing.w()))) * kDegPerRad;
}

/// The source with each sensor's gyro and acc axes turned by a uniformly random rotation of its
/// own (seeded): the same real motion as if every sensor had been strapped another way round.
class Restrapped final : public SampleSource {
 public:
  Restrapped(std::unique_ptr<SampleSource> src, unsigned seed) : src_(std::move(src)) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0, 1);
    for (Eigen::Quaterniond& q : turn_)
      q = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized();
  }
  const Config& config() const override { return src_->config(); }
  bool next(ImuSample& out) override {
    if (!src_->next(out)) return false;
    const Eigen::Quaterniond& q = turn_[static_cast<size_t>(out.sensor_id) % turn_.size()];
    out.gyr_rad_s = q * out.gyr_rad_s;
    out.acc_m_s2 = q * out.acc_m_s2;
    return true;
  }
  const std::string& error() const override { return src_->error(); }
  double progress() const override { return src_->progress(); }

 private:
  std::unique_ptr<SampleSource> src_;
  std::array<Eigen::Quaterniond, 64> turn_;
};

struct Knees {
  double left = 0, right = 0;                  ///< deg RMS off the hinge from 5 s
  std::array<int, kSegmentCount> big_turns{};  ///< frame-to-frame turns over 30 deg from 5 s
};

/// The run replayed with an N-pose at 2 s (restrap_seed > 0: every sensor turned at random).
Knees run_qmt(unsigned restrap_seed) {
  const std::string path =
      std::string(MOCAP_SHARED_DIR) + "/datasets/qmt-fullbody/fullbody_run.csv.gz";
  std::unique_ptr<SampleSource> src = open_sample_source(path, nullptr);
  if (restrap_seed > 0) src = std::make_unique<Restrapped>(std::move(src), restrap_seed);
  ReplayRun run(replay_config(*src, false, {"filter.use_mag=false"}, path), *src, path, false);
  KneeFrames frames;
  run.core.add_sink(&frames);
  ReplayOptions opt;
  opt.calibrate_pose = CalibrationPose::npose;
  opt.calibrate_at_s = 2.0;
  run_replay(*src, run.core, opt);
  EXPECT_TRUE(run.engine.skeleton().calibration().valid) << run.engine.last_calibration_message();
  EXPECT_GT(frames.f.size(), 9000u);
  Knees out;
  if (frames.f.empty()) return out;
  const int64_t t0 = frames.f.front().t_ns;
  double sum2[2] = {0, 0};
  int n = 0;
  for (size_t k = 1; k < frames.f.size(); ++k) {
    const PoseFrame& fr = frames.f[k];
    if (fr.t_ns - t0 < 5'000'000'000) continue;
    int side = 0;
    for (Segment shank : {Segment::shank_l, Segment::shank_r}) {
      const double off = off_hinge_deg(quat(fr.q_parent_segment[index(shank)]));
      sum2[side++] += off * off;
    }
    ++n;
    for (int s = 0; s < kSegmentCount; ++s) {
      const Eigen::Quaterniond a = quat(frames.f[k - 1].q_earth_segment[s]);
      const Eigen::Quaterniond b = quat(fr.q_earth_segment[s]);
      if (a.angularDistance(b) > 30 * kRadPerDeg) ++out.big_turns[s];
    }
  }
  out.left = std::sqrt(sum2[0] / n);
  out.right = std::sqrt(sum2[1] / n);
  return out;
}

TEST(QmtFullBody, KneesStayNearTheirHingeAndNothingFlips) {
  // Per segment: frame-to-frame turns over 30 deg after the still start (a flip, or a facing
  // found from motion applied at once: the first hinge answers turned both thighs 73-78 deg in
  // one frame before they were slewed).
  const Knees k = run_qmt(0);
  const double left = k.left, right = k.right;
  RecordProperty("knee_l_off_axis_deg", std::to_string(left));
  RecordProperty("knee_r_off_axis_deg", std::to_string(right));
  // Measured 8.21 / 8.50 deg; 8.6 / 9.0 while the knees' first answers waited for full evidence
  // where a site prior gave the facing (the lab's straps put those 37-68 deg off: the knees 13.0
  // / 14.4 deg off their hinge from 5 to 15 s, 10.6 / 10.8 now). Before that (8.5-8.8 / 9.0-10.1
  // over calibrations at 1-3.5 s); 9.2 / 9.5 with
  // the knee axes solved once a second in one round (8.7-9.3 / 9.5-10.7 over those moments;
  // 9.1 / 9.4 with the first hinge answers applied in one frame); 8.9 / 10.0, and
  // 8.8-11.5 / 10.0-10.8 over those moments, before the axis fit's pose prior;
  // 9.9 / 11.6 with the knees' heading held at 10 s rather than 2 s;
  // 10.4 / 11.9 with the relative heading of the axis fit's rows
  // followed rather than fitted per window; 15.0 / 21.5 before the knees' relative heading was
  // held to the hinge and their axes fitted with it; 36.5 / 40.1 at the start of issue 28's
  // work, where the straps were taken to be on our standard sites; the goal of 8 is not met:
  // docs/accuracy.md).
  EXPECT_LT(left, 8.5);
  EXPECT_LT(right, 8.8);
  for (int s = 0; s < kSegmentCount; ++s)
    EXPECT_EQ(k.big_turns[s], 0) << kSegmentNames[s];
}

// Every sensor of the real run turned at random on its segment (strapped any way): no site gives
// a facing, or a wrong one, so each knee sits off its hinge until its axis fit's first answer,
// which then comes from less evidence (HingeAxisEstimator::kEarlyEvidence). Measured, seeds 2 /
// 4: left 8.62 / 8.70, right 8.42 / 9.03 deg; left 9.56 / 8.70, right 8.71 / 9.03 while an early
// answer was given only to a segment with no facing at all (not where it contradicted a site
// prior); left 10.38 / 10.43 with every first answer waiting for full evidence.
TEST(QmtFullBody, RestrappedAtRandomTheKneesStillFindTheirHinge) {
  for (unsigned seed : {2u, 4u}) {
    const Knees k = run_qmt(seed);
    RecordProperty("knee_l_off_axis_deg_seed_" + std::to_string(seed), std::to_string(k.left));
    RecordProperty("knee_r_off_axis_deg_seed_" + std::to_string(seed), std::to_string(k.right));
    EXPECT_LT(k.left, 9.5) << "seed " << seed;
    EXPECT_LT(k.right, 9.5) << "seed " << seed;
    for (int s = 0; s < kSegmentCount; ++s)
      EXPECT_EQ(k.big_turns[s], 0) << "seed " << seed << " " << kSegmentNames[s];
  }
}

}  // namespace
}  // namespace mocap::daemon
