// AttitudeFilter under impacts (heel strikes, landings: a shank or foot reads up to 15 g for a
// few samples, with a rotation jolt) on a sensor that is otherwise still, on a synthetic
// stream with truth. The inclination low-passes acc in the almost-inertial frame, where a
// strike's specific force sums to the velocity it changes: nothing over a strike that ends
// where it began. So the strikes must not pull the inclination (docs/filter.md, "Impacts").
#include <gtest/gtest.h>

#include <cmath>

#include "mocap/filter/attitude_filter.hpp"
#include "synth.hpp"

namespace mocap::test {
namespace {

constexpr double kStrikePeriodS = 0.7;  // one strike per step
constexpr double kStrikeS = 0.04;       // each lasts 40 ms (4 samples at 100 Hz)
constexpr double kFirstStrikeS = 5.003;

/// Phase of the strike under way at t (0..1), or -1 between strikes.
double strike_phase(double t) {
  if (t < kFirstStrikeS) return -1;
  const double u = std::fmod(t - kFirstStrikeS, kStrikePeriodS) / kStrikeS;
  return u < 1 ? u : -1;
}

/// A still, tilted sensor struck every step from 5 s to 35 s: over 40 ms a full sine period of
/// earth-frame acceleration, peak 15 g, along a direction 50 deg off the vertical (net velocity
/// change zero), and a turn about a horizontal sensor axis, peak 10 rad/s, that returns.
SynthConfig strike_config() {
  SynthConfig c;
  c.q0 = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(0.35, Eigen::Vector3d(1, 1, 0).normalized()));
  c.duration_s = 40;
  c.gyr_bias = Eigen::Vector3d(0.3, -0.2, 0.4) * kDeg;
  c.acc_lin = [](double t) -> Eigen::Vector3d {
    const double u = strike_phase(t);
    if (u < 0 || t > 35) return Eigen::Vector3d::Zero();
    return 15 * 9.81 * std::sin(2 * kPi * u) * Eigen::Vector3d(0.6, 0.45, 0.66).normalized();
  };
  c.gyr_true = [](double t) -> Eigen::Vector3d {
    const double u = strike_phase(t);
    if (u < 0 || t > 35) return Eigen::Vector3d::Zero();
    return 10.0 * std::sin(2 * kPi * u) * Eigen::Vector3d(1, 0, 0);
  };
  return c;
}

/// Largest inclination error from from_s on, degrees (6D).
double worst_strike_tilt_deg(const SynthStream& s, const FilterParams& p, double from_s) {
  AttitudeFilter f(p);
  double worst = 0;
  for (size_t i = 0; i < s.samples.size(); ++i) {
    ImuSample smp = s.samples[i];
    smp.valid &= ~kFieldMag;
    f.update(smp);
    if (smp.t_host_ns * 1e-9 >= from_s)
      worst = std::max(worst, tilt_deg(f.output().q_earth_sensor_6d, s.truth[i]));
  }
  return worst;
}

TEST(AttitudeImpacts, StrikesOnAStillSensorLeaveTheInclination) {
  const SynthStream s = make_stream(strike_config());
  // Through 30 s of strikes and after them, the inclination stays within half a degree.
  EXPECT_LT(worst_strike_tilt_deg(s, FilterParams{}, 4.0), 0.5);
  // The strikes are strong enough to matter: an inclination low-pass 30 times faster (or
  // acc taken in the sensor frame) is pulled by degrees.
  FilterParams fast;
  fast.inclination.tau_acc_s = 0.1;
  EXPECT_GT(worst_strike_tilt_deg(s, fast, 4.0), 3.0);
}

}  // namespace
}  // namespace mocap::test
