// Rig consensus of the reference field (filt::RigFieldConsensus) and the trust anchor
// (AttitudeFilter::anchor_heading() while the field is untrusted): five sensors on one body,
// four in the clean earth field, one (a hand) starting beside a magnet, then carried away.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "mocap/filter/attitude_filter.hpp"
#include "mocap/filter/rig_field_consensus.hpp"
#include "synth.hpp"

namespace mocap::test {
namespace {

constexpr int kSensors = 5;
constexpr int kHand = 4;
constexpr double kLeaveS = 10;  // the hand leaves the magnet (fades over 1 s)
constexpr double kAnchorS = 3;  // calibration (N-pose) taken here, when anchoring
constexpr double kDurationS = 45;

std::vector<SynthStream> make_rig() {
  std::vector<SynthStream> rig;
  for (int i = 0; i < kSensors; ++i) {
    SynthConfig c;
    c.duration_s = kDurationS;
    c.seed = 11 + i;
    c.q0 = Eigen::Quaterniond(Eigen::AngleAxisd(-1.1 + 0.5 * i, Eigen::Vector3d::UnitZ()) *
                              Eigen::AngleAxisd(0.2 * i - 0.3, Eigen::Vector3d::UnitX()));
    if (i == kHand) {
      // Still beside the magnet until kLeaveS (a self-consistent field: 11 % weaker, 23 deg
      // less dip, 39 deg east of north), then moved away with hand-like rotation.
      c.gyr_true = [](double t) -> Eigen::Vector3d {
        if (t < kLeaveS) return Eigen::Vector3d::Zero();
        const double u = t - kLeaveS;
        return Eigen::Vector3d(0.8 * std::sin(1.3 * u), 0.6 * std::sin(0.9 * u + 1),
                               0.7 * std::sin(0.6 * u + 2));
      };
      c.mag_earth = [](double t) -> Eigen::Vector3d {
        const double fade = t < kLeaveS ? 1.0 : std::max(0.0, 1.0 - (t - kLeaveS));
        return Eigen::Vector3d(0, 20, -45) + fade * Eigen::Vector3d(20, 5, 15);
      };
    }  // the others stand still (N-pose)
    rig.push_back(make_stream(c));
  }
  return rig;
}

struct RigRun {
  std::vector<std::vector<double>> err_deg;  ///< per sensor, per sample
  std::vector<AttitudeFilter> filters;
  bool hand_disturbed_near_magnet = true;  ///< flagged disturbed all through 7..10 s
  double hand_err_at_anchor_deg = 0;
};

RigRun run_rig(const std::vector<SynthStream>& rig, bool consensus, bool anchor,
               const FilterParams& fp = {}) {
  RigRun r;
  r.filters.assign(kSensors, AttitudeFilter(fp));
  r.err_deg.resize(kSensors);
  filt::RigFieldConsensus cons(kSensors);
  bool anchored = false;
  for (size_t k = 0; k < rig[0].samples.size(); ++k) {
    const int64_t t_ns = rig[0].samples[k].t_host_ns;
    const double t = t_ns * 1e-9;
    for (int i = 0; i < kSensors; ++i) {
      r.filters[i].update(rig[i].samples[k]);
      r.err_deg[i].push_back(heading_err_deg(r.filters[i].q_earth_sensor(), rig[i].truth[k]));
    }
    if (consensus) cons.step(t_ns, r.filters);
    if (anchor && !anchored && t >= kAnchorS) {
      anchored = true;
      r.hand_err_at_anchor_deg = r.err_deg[kHand].back();
      for (AttitudeFilter& f : r.filters)
        f.anchor_heading();
    }
    if (t > 7 && t < kLeaveS) r.hand_disturbed_near_magnet &= r.filters[kHand].mag_disturbed();
  }
  return r;
}

double mean_abs(const std::vector<double>& v, double from_s, double to_s, double ts = 0.01) {
  double s = 0;
  int n = 0;
  for (size_t k = 0; k < v.size(); ++k)
    if (k * ts >= from_s && k * ts < to_s) {
      s += std::abs(v[k]);
      ++n;
    }
  return n ? s / n : 0.0;
}

// The hand takes the magnet's self-consistent field as its reference on its own; the rig's
// median replaces it, so the hand is flagged disturbed beside the magnet and its heading
// follows the earth field as soon as it is away (on its own it stays rejected, gyro only, with
// the magnet-bent heading until a new field has been seen for 20 s of rotation).
TEST(RigConsensus, SensorStartingBesideMagnetGetsTheRigsReference) {
  const auto rig = make_rig();
  const RigRun with = run_rig(rig, true, false);
  const RigRun without = run_rig(rig, false, false);
  const AttitudeFilter& hand = with.filters[kHand];
  EXPECT_TRUE(hand.mag_reference_imposed());
  EXPECT_NEAR(hand.mag_reference_norm_uT(), std::hypot(20.0, 45.0), 1.0);
  EXPECT_TRUE(with.hand_disturbed_near_magnet);
  EXPECT_FALSE(without.hand_disturbed_near_magnet);  // its own (magnet) reference
  for (int i = 0; i < kHand; ++i)
    EXPECT_FALSE(with.filters[i].mag_reference_imposed()) << i;
  const double e_with = mean_abs(with.err_deg[kHand], kLeaveS + 2, 30);
  const double e_without = mean_abs(without.err_deg[kHand], kLeaveS + 2, 30);
  EXPECT_LT(e_with, 0.5 * e_without) << e_with << " vs " << e_without;
  EXPECT_LT(std::abs(with.err_deg[kHand].back()), 3.0);
  for (int i = 0; i < kHand; ++i)
    EXPECT_LT(mean_abs(with.err_deg[i], 10, kDurationS), 2.0) << i;
}

// A calibration taken at 3 s absorbed the hand's magnet-bent heading (no reference yet, a
// field unlike the later reference): the anchor keeps that heading error once the field is
// trusted again instead of turning the heading (which would turn the calibration wrong).
TEST(RigConsensus, TrustAnchorKeepsTheHeadingTheCalibrationTook) {
  const auto rig = make_rig();
  const RigRun r = run_rig(rig, true, true);
  const double e0 = r.hand_err_at_anchor_deg;
  EXPECT_GT(std::abs(e0), 15.0);  // the calibration took a bent heading
  double max_dev = 0;
  for (size_t k = 0; k < r.err_deg[kHand].size(); ++k)
    if (k * 0.01 > kLeaveS + 2) max_dev = std::max(max_dev, std::abs(r.err_deg[kHand][k] - e0));
  EXPECT_LT(max_dev, 3.0);
  EXPECT_FALSE(r.filters[kHand].anchor_trust_pending());
  EXPECT_NEAR(r.filters[kHand].anchor_trust_rad() / kDeg, e0, 3.0);
  for (int i = 0; i < kHand; ++i) {
    EXPECT_EQ(r.filters[i].anchor_trust_rad(), 0.0) << i;  // their field was the earth's
    EXPECT_LT(mean_abs(r.err_deg[i], 10, kDurationS), 2.0) << i;
  }
  // Without the trust anchor the field turns the hand's heading away from the calibration's.
  FilterParams off;
  off.anchor_trust_avg_s = 0;
  const RigRun plain = run_rig(rig, true, true, off);
  EXPECT_GT(std::abs(plain.err_deg[kHand].back() - plain.hand_err_at_anchor_deg), 15.0);
}

// No consensus without a majority of references; sensors without a magnetometer do not count.
TEST(RigConsensus, NeedsAMajorityOfReferences) {
  std::vector<AttitudeFilter> filters(kSensors);
  filt::RigFieldConsensus cons(kSensors, {.period_s = 0.0});
  SynthConfig c;
  c.duration_s = 8;
  const auto s = make_stream(c);
  // Two of five sensors see the magnetometer (and accept the field at 5 s).
  for (const auto& smp : s.samples) {
    for (int i = 0; i < kSensors; ++i) {
      ImuSample x = smp;
      if (i >= 2) x.valid &= ~kFieldMag;
      filters[i].update(x);
    }
    cons.step(smp.t_host_ns, filters);
  }
  // 2 of 2 sensors with a magnetometer: a majority, but fewer than min_sensors (3).
  EXPECT_TRUE(filters[0].mag_has_reference());
  EXPECT_FALSE(cons.have_consensus());
  EXPECT_EQ(cons.imposed_total(), 0);
  for (int i = 2; i < kSensors; ++i)
    EXPECT_FALSE(filters[i].mag_has_reference());
}

}  // namespace
}  // namespace mocap::test
