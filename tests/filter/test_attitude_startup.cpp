// AttitudeFilter start-up: the "no reference field yet" state (distinct from "disturbed"), and
// a sensor that starts beside a magnet and then leaves it, on synthetic streams with truth.
#include <gtest/gtest.h>

#include <cmath>

#include "mocap/filter/attitude_filter.hpp"
#include "synth.hpp"

namespace mocap::test {
namespace {

Eigen::Quaterniond start_attitude() {
  return Eigen::Quaterniond(Eigen::AngleAxisd(-1.1, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX()));
}

TEST(AttitudeStartup, NoReferenceFlagMarksStartupApartFromDisturbance) {
  SynthConfig c;
  c.q0 = start_attitude();
  c.duration_s = 50;
  // A magnet passes by at 30..32 s, after the reference was accepted.
  c.mag_earth = [](double t) -> Eigen::Vector3d {
    Eigen::Vector3d m(0, 20, -45);
    if (t > 30 && t < 32) m += Eigen::Vector3d(25, 0, 10);
    return m;
  };
  const auto s = make_stream(c);
  AttitudeFilter f;
  EXPECT_FALSE(f.output().flags.mag_no_reference);  // no magnetometer seen yet
  bool no_ref_early = true, disturbed_early = false, no_ref_late = false, flagged = false;
  for (const auto& smp : s.samples) {
    f.update(smp);
    const double t = smp.t_host_ns * 1e-9;
    const FilterOutput o = f.output();
    EXPECT_FALSE(o.flags.mag_no_reference && o.flags.mag_disturbed);  // two distinct states
    if (f.counters().mag_ok > 0) {
      EXPECT_EQ(o.flags.mag_reference, !o.flags.mag_no_reference);
    }
    if (t < 4) {
      no_ref_early &= o.flags.mag_no_reference;
      disturbed_early |= o.flags.mag_disturbed;
    }
    if (t > 10) no_ref_late |= o.flags.mag_no_reference;
    if (t > 30.2 && t < 32) flagged |= o.flags.mag_disturbed;
  }
  EXPECT_TRUE(no_ref_early);      // start-up: no reference field yet ...
  EXPECT_FALSE(disturbed_early);  // ... which is not a disturbance
  EXPECT_FALSE(no_ref_late);      // the static earth field became the reference
  EXPECT_TRUE(flagged);           // and a passing magnet is a disturbance, not start-up
  EXPECT_LT(std::abs(heading_err_deg(f.output().q_earth_sensor, s.truth.back())), 1.5);
}

TEST(AttitudeStartup, NoMagnetometerMeansNoReferenceFlagOff) {
  SynthConfig c;
  c.duration_s = 5;
  auto s = make_stream(c);
  AttitudeFilter f;
  for (auto smp : s.samples) {
    smp.valid &= ~kFieldMag;
    f.update(smp);
  }
  EXPECT_FALSE(f.output().flags.mag_no_reference);
  EXPECT_FALSE(f.output().flags.mag_disturbed);
}

TEST(AttitudeStartup, MagHeadingCorrectionOnceConverged) {
  // output().mag_heading_rad: the magnetometer's turn of the 6D orientation, NaN without a
  // magnetometer and during the first moments of start-up (heading not converged yet).
  SynthConfig c;
  c.q0 = start_attitude();
  c.duration_s = 5;
  c.gyr_true = [](double t) -> Eigen::Vector3d { return Eigen::Vector3d(0, 0, 0.5 * std::sin(t)); };
  const auto s = make_stream(c);
  AttitudeFilter f, no_mag;
  EXPECT_TRUE(std::isnan(f.output().mag_heading_rad));
  bool nan_at_first = false, finite_later = true;
  for (const auto& smp : s.samples) {
    f.update(smp);
    ImuSample six = smp;
    six.valid &= ~kFieldMag;
    no_mag.update(six);
    EXPECT_TRUE(std::isnan(no_mag.output().mag_heading_rad));
    const double t = smp.t_host_ns * 1e-9;
    if (t < 0.05) nan_at_first |= std::isnan(f.output().mag_heading_rad);
    if (t < 2) continue;
    finite_later &= std::isfinite(f.output().mag_heading_rad);
    const Eigen::Quaterniond turned = Eigen::Quaterniond(Eigen::AngleAxisd(
                                          f.output().mag_heading_rad, Eigen::Vector3d::UnitZ())) *
                                      f.output().q_earth_sensor_6d;
    EXPECT_LT(turned.angularDistance(f.output().q_earth_sensor), 1e-9);
  }
  EXPECT_TRUE(nan_at_first);
  EXPECT_TRUE(finite_later);
  // The start attitude's heading (-1.1 rad) comes from the magnetometer (the 6D frame starts at
  // the sensor's own heading).
  EXPECT_GT(std::abs(f.output().mag_heading_rad), 0.5);
}

// A still start: the first rest's bias is the mean of the whole rest from its first sample
// (rest is detected rest.min_t_s = 1.5 s later), with the uncertainty of that many rest
// updates. 2 s after a still start the bias is then within 0.03 deg/s of the truth; the rest
// updates alone, from 1.5 s on, leave about 0.06 deg/s of a 1 deg/s bias (their prior's pull).
TEST(AttitudeStartup, StillStartGivesTheBiasOfTheWholeRest) {
  SynthConfig c;
  c.q0 = start_attitude();
  c.duration_s = 2.0;
  c.gyr_bias = Eigen::Vector3d(0.8, -0.6, 1.0) * kDeg;
  const auto s = make_stream(c);
  AttitudeFilter f;
  for (auto smp : s.samples) {
    smp.valid &= ~kFieldMag;
    f.update(smp);
  }
  ASSERT_TRUE(f.output().flags.at_rest);
  const Eigen::Vector3d err_deg_s = (f.output().gyro_bias_rad_s - c.gyr_bias) / kDeg;
  EXPECT_LT(err_deg_s.cwiseAbs().maxCoeff(), 0.03) << err_deg_s.transpose();
}

// The sensor starts next to a magnet and moves around in its gradient (hand-like motion), so
// the field it sees changes in norm and direction; at 8 s it is carried away from the magnet.
// The magnet's field must not become the reference ("north"), and once away the heading must
// converge on the earth field.
TEST(AttitudeStartup, MagnetAtStartThenLeaving) {
  SynthConfig c;
  c.q0 = start_attitude();
  c.duration_s = 45;
  c.gyr_true = [](double t) -> Eigen::Vector3d {
    return Eigen::Vector3d(0.8 * std::sin(1.3 * t), 0.6 * std::sin(0.9 * t + 1),
                           0.7 * std::sin(0.6 * t + 2));
  };
  const double leave_s = 8;
  c.mag_earth = [leave_s](double t) -> Eigen::Vector3d {
    Eigen::Vector3d m(0, 20, -45);
    // Near the magnet: a 15-35 uT field whose direction turns as the sensor moves.
    const double fade = t < leave_s ? 1.0 : std::max(0.0, 1.0 - (t - leave_s));
    const double a = 0.8 * std::sin(0.7 * t), mag = 25 + 10 * std::sin(1.1 * t);
    m += fade * mag * Eigen::Vector3d(std::cos(a), std::sin(a), 0.3);
    return m;
  };
  const auto s = make_stream(c);
  AttitudeFilter f;
  bool ref_near_magnet = false, disturbed_late = false;
  double max_err_late = 0;
  for (size_t i = 0; i < s.samples.size(); ++i) {
    f.update(s.samples[i]);
    const double t = s.samples[i].t_host_ns * 1e-9;
    ASSERT_TRUE(f.output().q_earth_sensor.coeffs().allFinite());
    if (t > 1 && t < leave_s) ref_near_magnet |= !f.output().flags.mag_no_reference;
    if (t > 35) {
      disturbed_late |= f.output().flags.mag_disturbed || f.output().flags.mag_no_reference;
      max_err_late =
          std::max(max_err_late, std::abs(heading_err_deg(f.output().q_earth_sensor, s.truth[i])));
    }
  }
  EXPECT_FALSE(ref_near_magnet);  // an inconsistent field is never a reference
  EXPECT_FALSE(disturbed_late);   // the earth field is the reference once away
  EXPECT_LT(max_err_late, 3.0);
}

}  // namespace
}  // namespace mocap::test

namespace mocap::test {
namespace {

// Samples read in one burst at start-up (a serial buffer full of old data, stamped at the read
// time): the first interval the filter sees is microseconds. The tracked sample period must not
// lock on it — every time constant would be that many times too long, and the reference field
// would never be accepted (found in the demo under load) — but follow the real period.
TEST(AttitudeStartup, BurstAtStartDoesNotLockTheSamplePeriod) {
  SynthConfig c;
  c.q0 = start_attitude();
  c.duration_s = 20;
  c.gyr_true = [](double t) -> Eigen::Vector3d {
    return Eigen::Vector3d(0.3 * std::sin(t), 0.2 * std::cos(0.7 * t), 0.5 * std::sin(0.4 * t));
  };
  auto s = make_stream(c);
  AttitudeFilter clean, burst;
  const int64_t burst_end_ns = s.samples[20].t_host_ns;
  double clean_ref_s = -1, burst_ref_s = -1;
  for (size_t k = 0; k < s.samples.size(); ++k) {
    ImuSample smp = s.samples[k];
    clean.update(smp);
    // The first 20 samples all stamped at the 21st's time, the 21st 56 us after.
    if (k < 20) smp.t_host_ns = burst_end_ns;
    if (k == 20) smp.t_host_ns = burst_end_ns + 56'000;
    burst.update(smp);
    const double t = s.samples[k].t_host_ns * 1e-9;
    if (clean_ref_s < 0 && clean.output().flags.mag_reference) clean_ref_s = t;
    if (burst_ref_s < 0 && burst.output().flags.mag_reference) burst_ref_s = t;
  }
  ASSERT_GT(clean_ref_s, 0);
  ASSERT_GT(burst_ref_s, 0) << "the reference field was never accepted after the burst";
  EXPECT_LT(burst_ref_s, clean_ref_s + 1.0);
  EXPECT_LT(std::abs(heading_err_deg(burst.output().q_earth_sensor, s.truth.back())), 1.5);
}

}  // namespace
}  // namespace mocap::test
