// Sensor model: ideal sensors measure the true kinematics (gyro integrates to the true orientation,
// accelerometer double-integrates to the true mount trajectory), the field model has dip and
// decays around dipoles, errors are drawn per seed.
#include <gtest/gtest.h>

#include <cmath>

#include "mocap/core/units.hpp"
#include "mocap/sim/performer.hpp"

namespace mocap::sim {
namespace {

PerformerParams ideal_params(const char* motion) {
  PerformerParams p;
  p.motion = motion;
  p.loop = false;
  p.sensor = SensorModelParams::ideal();
  return p;
}

TEST(SensorModel, AtRestAccelerometerReadsGravityUpAndMagHasDip) {
  Performer perf(ideal_params("npose"));
  const double g = SensorModelParams{}.gravity_m_s2;
  for (int id = 0; id < Performer::kSensorCount; ++id) {
    const SensorKinematics k = perf.sensor_kinematics(id, 1.0);
    EXPECT_LT(k.w_sensor_rad_s.norm(), 1e-9);
    EXPECT_LT(k.a_earth_m_s2.norm(), 1e-6);
  }
  std::vector<ImuSample> out;
  perf.step_to(500'000'000, out);
  ASSERT_GE(out.size(), 15u * 49);
  for (const ImuSample& s : out) {
    const SensorKinematics k = perf.sensor_kinematics(s.sensor_id, s.t_host_ns * 1e-9);
    const Eigen::Vector3d f_earth = k.q_earth_sensor * s.acc_m_s2;
    EXPECT_NEAR(f_earth.z(), g, 1e-6);
    EXPECT_NEAR(f_earth.head<2>().norm(), 0, 1e-6);
    const Eigen::Vector3d b_earth = k.q_earth_sensor * s.mag_uT;
    EXPECT_NEAR(b_earth.norm(), 50, 1e-6);
    EXPECT_NEAR(std::atan2(-b_earth.z(), b_earth.head<2>().norm()) * kDegPerRad, 60, 1e-6);
    EXPECT_NEAR(b_earth.y(), 25, 1e-6);  // magnetic north = earth y (declination 0)
    EXPECT_TRUE(s.flags & kFlagSynthetic);
    EXPECT_EQ(s.valid, kFieldGyr | kFieldAcc | kFieldMag);
  }
}

// Integrating the ideal gyro at 1 kHz through an arm raise reproduces the true orientation.
TEST(SensorModel, IdealGyroIntegratesToTrueOrientation) {
  auto p = ideal_params("arm_raise");
  p.rate_hz = 1000;
  Performer perf(p);
  const int id = Performer::sensor_of(Segment::forearm_r);
  const double t0 = 3.0, t1 = 9.0;  // forward flexion to 120 and sideways abduction to 110
  Eigen::Quaterniond q = perf.sensor_kinematics(id, t0).q_earth_sensor;
  const double dt = 1.0 / p.rate_hz;
  Eigen::Vector3d w_prev = perf.sensor_kinematics(id, t0).w_sensor_rad_s;
  double max_rate = 0;
  for (double t = t0 + dt; t <= t1 + 1e-9; t += dt) {
    const Eigen::Vector3d w = perf.sensor_kinematics(id, t).w_sensor_rad_s;
    const Eigen::Vector3d rv = 0.5 * (w + w_prev) * dt;  // trapezoid, body frame
    q = q * Eigen::Quaterniond(Eigen::AngleAxisd(rv.norm(), rv.normalized()));
    w_prev = w;
    max_rate = std::max(max_rate, w.norm());
  }
  EXPECT_GT(max_rate, 1.0);  // the motion really rotates the arm
  const Eigen::Quaterniond truth = perf.sensor_kinematics(id, t1).q_earth_sensor;
  EXPECT_LT(Eigen::AngleAxisd(q.conjugate() * truth).angle() * kDegPerRad, 0.05);
}

// Rotating the ideal accelerometer into earth, removing gravity and integrating twice reproduces
// the off-axis mount's true path (including the centripetal and tangential parts).
TEST(SensorModel, IdealAccelerometerDoubleIntegratesToMountTrajectory) {
  auto p = ideal_params("walk");
  p.rate_hz = 1000;
  Performer perf(p);
  const double g = p.sensor.gravity_m_s2;
  for (Segment seg : {Segment::forearm_l, Segment::shank_r, Segment::foot_l}) {
    const int id = Performer::sensor_of(seg);
    const double t0 = 5.0, t1 = 6.0, dt = 1.0 / p.rate_hz;
    const SensorKinematics k0 = perf.sensor_kinematics(id, t0);
    const SensorKinematics k0b = perf.sensor_kinematics(id, t0 + 1e-4);
    Eigen::Vector3d pos = k0.p_earth_m;
    Eigen::Vector3d vel = (k0b.p_earth_m - k0.p_earth_m) / 1e-4 + 0.5e-4 * k0.a_earth_m_s2;
    double max_acc = 0;
    auto lin_acc = [&](double t) {
      const SensorKinematics k = perf.sensor_kinematics(id, t);
      // Ideal measurement: specific force in the sensor frame, as the error model computes it.
      const Eigen::Vector3d f_sensor =
          k.q_earth_sensor.conjugate() * (k.a_earth_m_s2 + Eigen::Vector3d(0, 0, g));
      return Eigen::Vector3d(k.q_earth_sensor * f_sensor - Eigen::Vector3d(0, 0, g));
    };
    Eigen::Vector3d a_prev = lin_acc(t0);
    for (double t = t0 + dt; t <= t1 + 1e-9; t += dt) {
      const Eigen::Vector3d a = lin_acc(t);
      pos += vel * dt + (a_prev / 3 + a / 6) * dt * dt;
      vel += 0.5 * (a + a_prev) * dt;
      a_prev = a;
      max_acc = std::max(max_acc, a.norm());
    }
    EXPECT_GT(max_acc, 2.0) << name(seg);
    EXPECT_LT((pos - perf.sensor_kinematics(id, t1).p_earth_m).norm(), 0.005) << name(seg);
  }
}

TEST(SensorModel, OffAxisMountSeesCentripetalAcceleration) {
  // During the abduction the forearm sensor is ~0.6 m from the shoulder: its acceleration
  // differs from the forearm origin's (elbow) acceleration by the rotation-induced terms.
  Performer perf(ideal_params("arm_raise"));
  const int id = Performer::sensor_of(Segment::forearm_l);
  const double t = 3.0 + 3.0 + 1.3;  // abduction rising fast
  const SensorKinematics k = perf.sensor_kinematics(id, t);
  const double w = k.w_sensor_rad_s.norm();
  EXPECT_GT(w, 0.5);
  // Centripetal part alone about the shoulder: w^2 * r with r >= 0.4 m.
  EXPECT_GT(k.a_earth_m_s2.norm(), 0.3 * w * w);
}

TEST(SensorModel, PelvisBeltMountLooksForwardAlongMinusZ) {
  SensorModelParams p;
  p.mount_misalignment_deg = 0;
  std::mt19937_64 rng(3);
  const auto dims = body_dimensions_from_height(1.75);
  const SensorMount m = make_mount(Segment::pelvis, dims, p, rng);
  const Eigen::Vector3d fwd = m.q_segment_sensor * pelvis_forward_axis_sensor();
  EXPECT_LT((fwd - Eigen::Vector3d::UnitX()).norm(), 1e-12);
  EXPECT_LT((m.q_segment_sensor * Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitZ()).norm(),
            1e-12);
  // Other segments get random strap rolls: two seeds give different mounts.
  std::mt19937_64 r1(1), r2(2);
  const SensorMount a = make_mount(Segment::thigh_l, dims, p, r1);
  const SensorMount b = make_mount(Segment::thigh_l, dims, p, r2);
  EXPECT_GT(a.q_segment_sensor.angularDistance(b.q_segment_sensor), 1e-3);
  EXPECT_LT((a.q_segment_sensor * Eigen::Vector3d::UnitZ() -
             b.q_segment_sensor * Eigen::Vector3d::UnitZ())
                .norm(),
            1e-12);  // same normal
}

TEST(MagneticField, DipoleDecaysWithDistanceAndPresetsAreNamed) {
  MagneticFieldParams f;
  f.dipoles = disturbance_preset("magnet", 1.75);
  ASSERT_EQ(f.dipoles.size(), 1u);
  const Eigen::Vector3d c = f.dipoles[0].p_earth_m;
  const Eigen::Vector3d e = f.earth_field_uT();
  const double near = (f.field_uT(c + Eigen::Vector3d(0.1, 0, 0)) - e).norm();
  const double far = (f.field_uT(c + Eigen::Vector3d(0.2, 0, 0)) - e).norm();
  EXPECT_NEAR(near / far, 8.0, 0.01);  // 1/r^3 on the same axis
  EXPECT_GT(near, 50);
  EXPECT_LT((f.field_uT(c + Eigen::Vector3d(3, 0, 0)) - e).norm(), 0.01);
  EXPECT_THROW(disturbance_preset("fridge", 1.75), std::invalid_argument);
  EXPECT_EQ(disturbance_preset("both", 1.75).size(), 2u);
}

TEST(SensorErrorModel, BiasNoiseAndScaleFollowTheParameters) {
  SensorModelParams p;
  SensorKinematics k;  // at rest, identity
  const Eigen::Vector3d b(0, 20, -40);
  // Across many sensors (seeds) the turn-on gyro bias has the configured spread.
  double sum_sq = 0;
  const int n = 400;
  for (int s = 0; s < n; ++s) {
    SensorErrorModel m(p, 100, 1000 + s);
    sum_sq += m.gyr_bias_rad_s().squaredNorm();
  }
  const double sigma_dps = std::sqrt(sum_sq / (3 * n)) * kDegPerRad;
  EXPECT_NEAR(sigma_dps, p.gyr_bias_sigma_dps, 0.1 * p.gyr_bias_sigma_dps);
  // Per-sample gyro noise around the bias: sigma = density * sqrt(rate).
  SensorErrorModel m(p, 100, 7);
  ImuSample s;
  double acc_sq = 0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  const int samples = 2000;
  for (int i = 0; i < samples; ++i) {
    m.measure(k, b, 0.0, s);  // dt 0: bias frozen
    mean += s.gyr_rad_s;
    acc_sq += (s.acc_m_s2 - Eigen::Vector3d(0, 0, p.gravity_m_s2)).squaredNorm();
  }
  mean /= samples;
  EXPECT_LT((mean - m.gyr_bias_rad_s()).norm() * kDegPerRad, 0.02);
  // Accelerometer error: bias (0.05) + scale (0.5% of g) + noise, per axis well under 0.3 m/s^2.
  EXPECT_LT(std::sqrt(acc_sq / samples), 0.3);
  EXPECT_GT(std::sqrt(acc_sq / samples), 0.001);
  // Deterministic per seed.
  SensorErrorModel m1(p, 100, 99), m2(p, 100, 99);
  ImuSample s1, s2;
  m1.measure(k, b, 0.01, s1);
  m2.measure(k, b, 0.01, s2);
  EXPECT_EQ(s1.gyr_rad_s, s2.gyr_rad_s);
  EXPECT_EQ(s1.mag_uT, s2.mag_uT);
}

TEST(SensorModel, SaturationClampsAndFlags) {
  SensorModelParams p = SensorModelParams::ideal();
  SensorErrorModel m(p, 100, 1);
  SensorKinematics k;
  k.w_sensor_rad_s = Eigen::Vector3d(50, 0, 0);  // 2865 deg/s > 2000
  ImuSample s;
  m.measure(k, Eigen::Vector3d(0, 20, -40), 0.01, s);
  EXPECT_NEAR(s.gyr_rad_s.x(), 2000 * kRadPerDeg, 1e-9);
  EXPECT_TRUE(s.flags & kFlagSaturated);
}

}  // namespace
}  // namespace mocap::sim
