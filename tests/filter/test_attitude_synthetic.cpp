// AttitudeFilter on synthetic streams with known truth: static, rotations, bias, linear
// acceleration, magnetic disturbances, gaps, multi-rate input and 25 Hz .. 2 kHz.
#include <gtest/gtest.h>

#include "mocap/filter/attitude_filter.hpp"
#include "synth.hpp"

namespace mocap::test {
namespace {

struct RunResult {
  double max_err_deg = 0, max_tilt_deg = 0, final_err_deg = 0;
  AttitudeFilter filter;
};

// Runs the filter and records the worst error after t_settle_s.
RunResult run(const SynthStream& s, double t_settle_s, const FilterParams& p = {}) {
  RunResult r{0, 0, 0, AttitudeFilter(p)};
  for (size_t i = 0; i < s.samples.size(); ++i) {
    r.filter.update(s.samples[i]);
    const Eigen::Quaterniond q = r.filter.output().q_earth_sensor;
    EXPECT_TRUE(q.coeffs().allFinite());
    if (s.samples[i].t_host_ns * 1e-9 < t_settle_s) continue;
    r.max_err_deg = std::max(r.max_err_deg, angle_deg(q, s.truth[i]));
    r.max_tilt_deg =
        std::max(r.max_tilt_deg, tilt_deg(r.filter.output().q_earth_sensor_6d, s.truth[i]));
    r.final_err_deg = angle_deg(q, s.truth[i]);
  }
  return r;
}

Eigen::Quaterniond some_attitude() {
  return Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()) *
                            Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitY()));
}

TEST(AttitudeSynthetic, StaticConvergesFastIncludingHeading) {
  SynthConfig c;
  c.q0 = some_attitude();
  c.duration_s = 20;
  const auto s = make_stream(c);
  const RunResult r = run(s, 2.0);
  EXPECT_LT(r.max_err_deg, 1.0);
  EXPECT_TRUE(r.filter.output().flags.at_rest);
  EXPECT_FALSE(r.filter.output().flags.mag_disturbed);
}

class ConstantRotation : public ::testing::TestWithParam<int> {};

TEST_P(ConstantRotation, TracksAboutEachAxis) {
  SynthConfig c;
  c.q0 = some_attitude();
  c.duration_s = 30;
  const int axis = GetParam();
  c.gyr_true = [axis](double t) -> Eigen::Vector3d {
    Eigen::Vector3d w = Eigen::Vector3d::Zero();
    if (t > 5) w[axis] = 90 * kDeg;
    return w;
  };
  const RunResult r = run(make_stream(c), 2.0);
  EXPECT_LT(r.max_err_deg, 2.0) << "axis " << axis;
  EXPECT_LT(r.max_tilt_deg, 1.0) << "axis " << axis;
}

INSTANTIATE_TEST_SUITE_P(Axes, ConstantRotation, ::testing::Values(0, 1, 2));

TEST(AttitudeSynthetic, EstimatesGyroBiasAtRestAndDuringMotion) {
  SynthConfig c;
  c.q0 = some_attitude();
  c.duration_s = 120;
  c.gyr_bias = Eigen::Vector3d(0.5, -0.3, 0.4) * kDeg;
  const auto rest = run(make_stream(c), 5.0);
  EXPECT_LT((rest.filter.output().gyro_bias_rad_s - c.gyr_bias).norm() / kDeg, 0.05);
  EXPECT_LT(rest.max_err_deg, 2.0);
  // Slow continuous motion from the start: the motion update estimates horizontal bias.
  c.gyr_true = [](double t) -> Eigen::Vector3d {
    return Eigen::Vector3d(0.4 * std::sin(0.5 * t), 0.3 * std::cos(0.37 * t), 0.2);
  };
  const auto moving = run(make_stream(c), 30.0);
  EXPECT_LT(moving.max_tilt_deg, 1.5);
  EXPECT_LT(moving.max_err_deg, 4.0);
}

TEST(AttitudeSynthetic, LinearAccelerationBurstsDoNotTilt) {
  SynthConfig c;
  c.q0 = some_attitude();
  c.duration_s = 40;
  // 1 s bursts of +-5 m/s^2 horizontal acceleration every 4 s (zero-mean velocity change).
  c.acc_lin = [](double t) -> Eigen::Vector3d {
    const double ph = std::fmod(t, 4.0);
    if (t < 5 || ph > 1.0) return Eigen::Vector3d::Zero().eval();
    return Eigen::Vector3d(5 * std::sin(2 * kPi * ph), 3 * std::sin(2 * kPi * ph), 0);
  };
  c.gyr_true = [](double t) -> Eigen::Vector3d {
    return Eigen::Vector3d(0, 0, 0.3 * std::sin(0.8 * t));
  };
  const RunResult r = run(make_stream(c), 2.0);
  EXPECT_LT(r.max_tilt_deg, 1.0);
  EXPECT_LT(r.max_err_deg, 2.0);
}

TEST(AttitudeSynthetic, MagnetPassingByIsRejected) {
  SynthConfig c;
  c.q0 = some_attitude();
  c.duration_s = 60;
  c.gyr_true = [](double t) -> Eigen::Vector3d {
    return Eigen::Vector3d(0.3 * std::sin(0.6 * t), 0, 0.5 * std::sin(0.4 * t));
  };
  // A magnet passes between 30 and 34 s: a strong extra field that swings in direction.
  c.mag_earth = [](double t) -> Eigen::Vector3d {
    Eigen::Vector3d m(0, 20, -45);
    if (t > 30 && t < 34) {
      const double s = std::sin(kPi * (t - 30) / 4);
      m += Eigen::Vector3d(60 * s, -30 * s, 20 * s);
    }
    return m;
  };
  const auto s = make_stream(c);
  AttitudeFilter f;
  bool flagged = false;
  double max_err = 0, max_tilt = 0;
  for (size_t i = 0; i < s.samples.size(); ++i) {
    f.update(s.samples[i]);
    const double t = s.samples[i].t_host_ns * 1e-9;
    if (t > 31 && t < 33) flagged |= f.output().flags.mag_disturbed;
    if (t > 10) {
      max_err = std::max(max_err, angle_deg(f.output().q_earth_sensor, s.truth[i]));
      max_tilt = std::max(max_tilt, tilt_deg(f.output().q_earth_sensor, s.truth[i]));
    }
  }
  EXPECT_TRUE(flagged);
  EXPECT_LT(max_err, 3.0);
  EXPECT_LT(max_tilt, 1.0);  // the magnetometer never tilts the inclination
}

TEST(AttitudeSynthetic, StepInFieldIsRejectedThenAccepted) {
  SynthConfig c;
  c.q0 = some_attitude();
  c.duration_s = 120;
  c.gyr_true = [](double t) -> Eigen::Vector3d {
    return Eigen::Vector3d(0.5 * std::sin(0.7 * t), 0.4 * std::cos(0.5 * t), 0.6);
  };
  // At 30 s the field norm jumps by 40 % (e.g. moved into a different room); direction kept.
  c.mag_earth = [](double t) -> Eigen::Vector3d {
    return Eigen::Vector3d(0, 20, -45) * (t > 30 ? 1.4 : 1.0);
  };
  const auto s = make_stream(c);
  AttitudeFilter f;
  bool flagged = false, accepted_again = false;
  double max_err = 0;
  for (size_t i = 0; i < s.samples.size(); ++i) {
    f.update(s.samples[i]);
    const double t = s.samples[i].t_host_ns * 1e-9;
    if (t > 31 && t < 35) flagged |= f.output().flags.mag_disturbed;
    if (t > 110) accepted_again |= !f.output().flags.mag_disturbed;
    if (t > 10) max_err = std::max(max_err, angle_deg(f.output().q_earth_sensor, s.truth[i]));
  }
  EXPECT_TRUE(flagged);
  EXPECT_TRUE(accepted_again);
  EXPECT_LT(max_err, 3.0);
}

TEST(AttitudeSynthetic, GapsUseTimestamps) {
  SynthConfig c;
  c.q0 = some_attitude();
  c.duration_s = 40;
  c.gyr_true = [](double t) -> Eigen::Vector3d {
    return Eigen::Vector3d(0.3, -0.2, 0.5 * std::sin(0.5 * t));
  };
  auto s = make_stream(c);
  // Drop 3 of every 50 samples (lost packets): the timestamps carry the longer periods.
  SynthStream g;
  for (size_t i = 0; i < s.samples.size(); ++i)
    if (i % 50 >= 3) {
      g.samples.push_back(s.samples[i]);
      g.truth.push_back(s.truth[i]);
    }
  const RunResult r = run(g, 2.0);
  EXPECT_LT(r.max_err_deg, 2.0);
  EXPECT_EQ(r.filter.counters().bad_time, 0u);
}

// The 6D heading error's change across a gap of samples [from_s, to_s) in a level sensor
// turning about the vertical at gyr_z(t): the rotation the filter missed or made up.
double heading_change_across_gap_deg(const std::function<double(double)>& gyr_z, double from_s,
                                     double to_s) {
  SynthConfig c;
  c.duration_s = to_s + 1;
  c.gyr_noise = 0;
  c.gyr_true = [&](double t) -> Eigen::Vector3d { return Eigen::Vector3d(0, 0, gyr_z(t)); };
  const SynthStream s = make_stream(c);
  AttitudeFilter f;
  Eigen::Quaterniond e_before = Eigen::Quaterniond::Identity();
  for (size_t i = 0; i < s.samples.size(); ++i) {
    const double t = s.samples[i].t_host_ns * 1e-9;
    if (t >= from_s && t < to_s) continue;
    f.update(s.samples[i]);
    const Eigen::Quaterniond e = f.output().q_earth_sensor_6d * s.truth[i].conjugate();
    if (t < from_s) e_before = e;
    if (t >= to_s) return angle_deg(e, e_before);
  }
  return -1;
}

// A gap longer than kMaxGap_s (0.25 s) is not integrated: holding the newest rate over it
// made up a turn. The sensor turns back and forth, 0.5 s a period, and misses one period from
// its fastest turn on: it ends where it began but for the period before the gap (1.7 deg), and
// the filter turns nothing (holding 3 rad/s for 0.25 s made up 43 deg).
TEST(AttitudeSynthetic, AGapTooLongToBridgeIsNotGuessed) {
  const auto gyr_z = [](double t) { return 3.0 * std::cos(2 * kPi * t / 0.5); };
  EXPECT_LT(heading_change_across_gap_deg(gyr_z, 10.0, 10.5), 3.0);
}

// A shorter gap takes the rate as changing in a straight line between the samples either
// side: exact for a rate ramping 10 rad/s^2 (holding the newest rate: 6 deg too far).
TEST(AttitudeSynthetic, AShortGapTakesTheMeanRateOfItsEnds) {
  const auto gyr_z = [](double t) { return std::clamp(10.0 * (t - 10.0), 0.0, 3.0); };
  EXPECT_LT(heading_change_across_gap_deg(gyr_z, 10.06, 10.2), 1.0);
}

class Rates : public ::testing::TestWithParam<double> {};

TEST_P(Rates, SameAccuracyFrom25HzTo2kHz) {
  SynthConfig c;
  c.rate_hz = GetParam();
  c.q0 = some_attitude();
  c.duration_s = 30;
  c.gyr_true = [](double t) -> Eigen::Vector3d {
    return Eigen::Vector3d(0.6 * std::sin(0.9 * t), 0.4 * std::cos(0.6 * t),
                           0.5 * std::sin(0.3 * t));
  };
  const RunResult r = run(make_stream(c), 2.0);
  EXPECT_LT(r.max_err_deg, 2.0) << c.rate_hz << " Hz";
}

INSTANTIATE_TEST_SUITE_P(Hz, Rates, ::testing::Values(25.0, 100.0, 285.7, 1000.0, 2000.0));

TEST(AttitudeSynthetic, SlowerMagnetometerInSeparateSamples) {
  SynthConfig c;
  c.rate_hz = 200;
  c.mag_every = 4;  // 50 Hz magnetometer
  c.q0 = some_attitude();
  c.duration_s = 30;
  c.gyr_true = [](double t) -> Eigen::Vector3d {
    return Eigen::Vector3d(0.2, 0.5 * std::sin(t), 0.4);
  };
  const RunResult r = run(make_stream(c), 2.0);
  EXPECT_LT(r.max_err_deg, 2.0);
  EXPECT_GT(r.filter.counters().mag_ok, 1000u);
  EXPECT_EQ(r.filter.counters().bad_time, 0u);
}

TEST(AttitudeSynthetic, SavedStateReproducesOutput) {
  SynthConfig c;
  c.q0 = some_attitude();
  c.duration_s = 20;
  c.gyr_true = [](double t) -> Eigen::Vector3d {
    return Eigen::Vector3d(0.3, 0.1, 0.5 * std::sin(t));
  };
  const auto s = make_stream(c);
  AttitudeFilter a;
  const size_t half = s.samples.size() / 2;
  for (size_t i = 0; i < half; ++i)
    a.update(s.samples[i]);
  AttitudeFilter b;
  b.set_state(a.state());
  for (size_t i = half; i < s.samples.size(); ++i) {
    a.update(s.samples[i]);
    b.update(s.samples[i]);
  }
  EXPECT_LT(a.output().q_earth_sensor.angularDistance(b.output().q_earth_sensor), 1e-12);
  EXPECT_EQ(a.output().gyro_bias_rad_s, b.output().gyro_bias_rad_s);
}

TEST(AttitudeSynthetic, SixDimensionalOutputBeforeMagnetometer) {
  SynthConfig c;
  c.q0 = some_attitude();
  c.duration_s = 5;
  auto s = make_stream(c);
  AttitudeFilter f;
  for (auto smp : s.samples) {
    smp.valid &= static_cast<uint8_t>(~kFieldMag);
    f.update(smp);
  }
  EXPECT_LT(tilt_deg(f.output().q_earth_sensor, s.truth.back()), 0.5);
  EXPECT_GT(f.output().heading_sigma_rad, 1.0);  // heading unknown without a magnetometer
}

}  // namespace
}  // namespace mocap::test
