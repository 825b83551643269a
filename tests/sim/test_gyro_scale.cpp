// Gyro scale calibration (estimate_gyro_scale) on the virtual sensor's table spins
// (sim::table_spin_samples): each axis's drawn scale error is recovered, with the bias, noise
// and hard-iron offset of the consumer-MEMS model, also when the sensor is put back turned
// (the magnetometer gives the net turn); motions that are not a clean spin are rejected.
#include <gtest/gtest.h>

#include "mocap/filter/gyro_scale.hpp"
#include "mocap/sim/sensor_model.hpp"
#include "mocap/sim/table_spin.hpp"

namespace mocap::sim {
namespace {

TEST(GyroScale, TableSpinsRecoverEveryAxisScale) {
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    SensorErrorModel model(SensorModelParams{}, 100, seed);
    const auto samples = table_spin_samples(model, MagneticFieldParams{}, 100);
    const GyroScaleResult r = estimate_gyro_scale(samples);
    for (int ax = 0; ax < 3; ++ax) {
      EXPECT_EQ(r.axis[ax].spins, 1) << "seed " << seed << " axis " << ax;
      // Drawn errors are ~0.5 % (1 sigma); recovered to 0.05 %.
      EXPECT_NEAR(r.axis[ax].scale, model.gyr_scale()[ax], 5e-4)
          << "seed " << seed << " axis " << ax;
    }
    EXPECT_EQ(r.rejected_spins, 2);  // the two flips between the axes
  }
}

TEST(GyroScale, PutBackTurnedTheMagnetometerGivesTheNetTurn) {
  SensorErrorModel model(SensorModelParams{}, 100, 7);
  // 3 turns and 25 deg: without the magnetometer that is read as 3 turns (0.8 % error).
  const auto samples = table_spin_samples(model, MagneticFieldParams{}, 100, 3, 25);
  const GyroScaleResult r = estimate_gyro_scale(samples);
  std::vector<ImuSample> no_mag = samples;
  for (ImuSample& s : no_mag)
    s.valid &= ~kFieldMag;
  const GyroScaleResult blind = estimate_gyro_scale(no_mag);
  for (int ax = 0; ax < 3; ++ax) {
    EXPECT_NEAR(r.axis[ax].scale, model.gyr_scale()[ax], 1e-3) << "axis " << ax;
    EXPECT_GT(std::abs(blind.axis[ax].scale - model.gyr_scale()[ax]), 0.015) << "axis " << ax;
  }
}

TEST(GyroScale, NoSpinsLeaveTheScaleAtOne) {
  SensorErrorModel model(SensorModelParams{}, 100, 3);
  auto samples = table_spin_samples(model, MagneticFieldParams{}, 100, 0, 180);  // half turns
  const GyroScaleResult r = estimate_gyro_scale(samples);
  EXPECT_EQ(r.scale(), Eigen::Vector3d::Ones());
  EXPECT_EQ(r.rejected_spins, 5);
  EXPECT_EQ(r.rests, 6);
}

}  // namespace
}  // namespace mocap::sim
