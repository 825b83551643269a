// AttitudeFilter hard-iron estimation on synthetic streams with truth: a magnet attached to
// the sensor after start-up during hand-like rotation (offset recovered, heading kept), no
// offset invented without one, and a magnet that is removed again.
#include <gtest/gtest.h>

#include "mocap/filter/attitude_filter.hpp"
#include "synth.hpp"

namespace mocap::test {
namespace {

// Hand-like rotation: about all axes, 1-1.5 rad/s peaks, periods 6-13 s.
SynthConfig hand_motion(double duration_s) {
  SynthConfig c;
  c.q0 = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()));
  c.duration_s = duration_s;
  c.gyr_true = [](double t) -> Eigen::Vector3d {
    return Eigen::Vector3d(1.5 * std::sin(1.1 * t), 1.2 * std::sin(0.7 * t + 1),
                           1.0 * std::sin(0.5 * t + 2));
  };
  return c;
}

// Adds a sensor-fixed offset to every magnetometer sample in [t0, t1).
void add_offset(SynthStream& s, const Eigen::Vector3d& h_uT, double t0_s, double t1_s) {
  for (auto& smp : s.samples) {
    const double t = smp.t_host_ns * 1e-9;
    if ((smp.valid & kFieldMag) && t >= t0_s && t < t1_s) smp.mag_uT += h_uT;
  }
}

struct HiRun {
  double max_err_deg = 0;  ///< after t_from_s
  double disturbed_fraction = 0;
  AttitudeFilter f;
};

HiRun run_filter(const SynthStream& s, double t_from_s, double t_to_s, const FilterParams& p = {}) {
  HiRun r{0, 0, AttitudeFilter(p)};
  int n = 0, dist = 0;
  for (size_t i = 0; i < s.samples.size(); ++i) {
    r.f.update(s.samples[i]);
    EXPECT_TRUE(r.f.output().q_earth_sensor.coeffs().allFinite());
    const double t = s.samples[i].t_host_ns * 1e-9;
    if (t < t_from_s || t >= t_to_s) continue;
    r.max_err_deg = std::max(r.max_err_deg, angle_deg(r.f.output().q_earth_sensor, s.truth[i]));
    ++n;
    dist += r.f.output().flags.mag_disturbed;
  }
  r.disturbed_fraction = n > 0 ? static_cast<double>(dist) / n : 0;
  return r;
}

TEST(AttitudeHardIron, MagnetAttachedAfterStartupIsEstimatedAndRemoved) {
  auto s = make_stream(hand_motion(90));
  const Eigen::Vector3d h(10, -5, 8);  // 14 uT, about 30 % of the earth field
  add_offset(s, h, 20, 1e9);
  const HiRun on = run_filter(s, 40, 1e9);
  EXPECT_LT((on.f.output().hard_iron_uT - h).norm(), 1.5);
  EXPECT_LT(on.f.output().hard_iron_sigma_uT, 1.5);
  EXPECT_LT(on.max_err_deg, 2.5);
  EXPECT_LT(on.disturbed_fraction, 0.1);  // the corrected field is accepted again
  // Without the estimate the same stream is rejected (gyro only) or followed with the magnet.
  FilterParams off;
  off.hard_iron.tau_s = 0;
  const HiRun no = run_filter(s, 40, 1e9, off);
  EXPECT_GT(no.disturbed_fraction, 0.5);
  EXPECT_EQ(no.f.output().hard_iron_uT, Eigen::Vector3d::Zero());
}

TEST(AttitudeHardIron, NoOffsetIsInventedWithoutAMagnet) {
  const auto s = make_stream(hand_motion(90));
  const HiRun r = run_filter(s, 10, 1e9);
  EXPECT_LT(r.f.output().hard_iron_uT.norm(), 0.5);
  EXPECT_LT(r.max_err_deg, 1.5);
  EXPECT_EQ(r.disturbed_fraction, 0.0);
}

TEST(AttitudeHardIron, MagnetRemovedAgainIsForgotten) {
  auto s = make_stream(hand_motion(120));
  add_offset(s, Eigen::Vector3d(-6, 12, -9), 20, 60);
  const HiRun r = run_filter(s, 90, 1e9);
  EXPECT_LT(r.f.output().hard_iron_uT.norm(), 1.0);
  EXPECT_LT(r.max_err_deg, 2.5);
  EXPECT_LT(r.disturbed_fraction, 0.1);
}

}  // namespace
}  // namespace mocap::test
