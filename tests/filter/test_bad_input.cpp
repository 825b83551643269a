// Bad input never reaches the filter state: NaN/Inf, zero vectors, absurd magnitudes and
// timestamps that go backwards are rejected and counted; outputs stay finite.
#include <gtest/gtest.h>

#include <limits>

#include "mocap/eval/madgwick.hpp"
#include "mocap/eval/mahony.hpp"
#include "mocap/filter/attitude_filter.hpp"
#include "synth.hpp"

namespace mocap::test {
namespace {

SynthStream clean() {
  SynthConfig c;
  c.duration_s = 20;
  c.q0 = Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitX()));
  c.gyr_true = [](double t) -> Eigen::Vector3d {
    return Eigen::Vector3d(0.2, 0.1, 0.3 * std::sin(t));
  };
  return make_stream(c);
}

// Every 7th sample is corrupted in one of several ways.
void corrupt(ImuSample& s, size_t i) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  switch (i % 7) {
    case 0:
      s.gyr_rad_s.x() = nan;
      break;
    case 1:
      s.acc_m_s2.y() = inf;
      break;
    case 2:
      s.mag_uT.setZero();
      break;
    case 3:
      s.acc_m_s2.setZero();
      break;
    case 4:
      s.mag_uT *= 1e6;
      break;
    case 5:
      s.gyr_rad_s *= 1e4;
      s.gyr_rad_s.x() += 1e3;
      break;
    case 6:
      s.acc_m_s2.z() = -inf;
      s.mag_uT.x() = nan;
      break;
  }
}

TEST(BadInput, RejectedCountedAndNeverNaN) {
  const auto s = clean();
  AttitudeFilter f;
  double max_err = 0;
  for (size_t i = 0; i < s.samples.size(); ++i) {
    ImuSample smp = s.samples[i];
    if (i % 5 == 0) corrupt(smp, i / 5);
    f.update(smp);
    ASSERT_TRUE(f.output().q_earth_sensor.coeffs().allFinite()) << i;
    ASSERT_TRUE(f.output().q_earth_sensor_6d.coeffs().allFinite()) << i;
    ASSERT_TRUE(f.output().gyro_bias_rad_s.allFinite()) << i;
    ASSERT_TRUE(std::isfinite(f.output().heading_sigma_rad));
    if (i > 500) max_err = std::max(max_err, angle_deg(f.output().q_earth_sensor, s.truth[i]));
  }
  const auto& c = f.counters();
  EXPECT_GT(c.nonfinite, 0u);
  EXPECT_GT(c.zero_vector, 0u);
  EXPECT_GT(c.out_of_range, 0u);
  EXPECT_LT(max_err, 3.0);  // still tracks with a fifth of the samples damaged
}

TEST(BadInput, TimestampGoingBackwardsIsRejected) {
  const auto s = clean();
  AttitudeFilter f;
  for (size_t i = 0; i < 300; ++i)
    f.update(s.samples[i]);
  ImuSample old = s.samples[100];
  f.update(old);
  EXPECT_GT(f.counters().bad_time, 0u);
  f.update(s.samples[300]);
  EXPECT_LT(angle_deg(f.output().q_earth_sensor, s.truth[300]), 2.0);
}

TEST(BadInput, OnlyGarbageKeepsIdentityAndFinite) {
  AttitudeFilter f;
  ImuSample s;
  s.valid = kFieldGyr | kFieldAcc | kFieldMag;
  s.gyr_rad_s.setConstant(std::numeric_limits<double>::quiet_NaN());
  for (int i = 0; i < 100; ++i) {
    s.t_host_ns = i * 10'000'000;
    f.update(s);
  }
  EXPECT_TRUE(f.output().q_earth_sensor.coeffs().allFinite());
  EXPECT_EQ(f.counters().gyr_ok, 0u);
  EXPECT_EQ(f.counters().acc_ok, 0u);  // zero acc and mag
  EXPECT_EQ(f.counters().zero_vector, 200u);
}

TEST(BadInput, BaselinesStayFinite) {
  const auto s = clean();
  MadgwickFilter mad;
  MahonyFilter mah;
  for (size_t i = 0; i < s.samples.size(); ++i) {
    ImuSample smp = s.samples[i];
    if (i % 5 == 0) corrupt(smp, i / 5);
    mad.update(smp);
    mah.update(smp);
    ASSERT_TRUE(mad.q_earth_sensor().coeffs().allFinite());
    ASSERT_TRUE(mah.q_earth_sensor().coeffs().allFinite());
  }
  EXPECT_GT(mad.counters().nonfinite, 0u);
  EXPECT_GT(mah.counters().out_of_range, 0u);
}

}  // namespace
}  // namespace mocap::test
