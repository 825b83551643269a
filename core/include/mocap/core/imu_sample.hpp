// The IMU sample: what every driver produces and every later stage consumes. SI units, sensor
// frame, host-monotonic timestamps. Plain value type (no heap members) so it can cross lock-free
// queues.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <type_traits>

namespace mocap {

/// Which measurement fields of an ImuSample hold data (bit set).
enum SampleField : uint8_t {
  kFieldGyr = 1u << 0,   ///< gyr_rad_s is valid
  kFieldAcc = 1u << 1,   ///< acc_m_s2 is valid
  kFieldMag = 1u << 2,   ///< mag_uT is valid
  kFieldQuat = 1u << 3,  ///< q_device_sensor (the device's own orientation estimate) is valid
};

/// Conditions a driver observed around this sample (bit set).
enum SampleFlag : uint8_t {
  kFlagGapBefore = 1u << 0,     ///< samples were lost just before this one (counter jumped)
  kFlagClockReset = 1u << 1,    ///< the device clock jumped or restarted; time mapping re-synced
  kFlagSaturated = 1u << 2,     ///< at least one axis is at its full-scale limit
  kFlagSynthetic = 1u << 3,     ///< produced by a simulator, not hardware
  kFlagInterpolated = 1u << 4,  ///< filled in (e.g. mag held from a slower stream)
  kFlagImplausible = 1u << 5,   ///< a field beyond the sensor's range was dropped (a glitch)
  kFlagGyrClipped = 1u << 6,  ///< a gyro axis is at its limit (with kFlagSaturated): rotation lost
  /// The device restarted (a tracker that rebooted): its own orientation (q_device_sensor)
  /// starts in a new frame, its heading unrelated to the one before.
  kFlagDeviceRestarted = 1u << 7,
};

/// One time instant of one inertial sensor, after unit conversion and axis remapping.
///
/// Frames: all vectors are in the sensor frame (right-handed, as printed on the housing after
/// the rig's axis remap). Units: gyro rad/s, accelerometer m/s^2 of specific force (reads about
/// +9.81 on the up axis at rest), magnetometer microtesla (or arbitrary units with a consistent
/// scale when the device does not say: only direction and relative norm matter to the filter).
struct ImuSample {
  int64_t t_host_ns = 0;    ///< host CLOCK_MONOTONIC time of the measurement, ns (drift-tracked)
  int64_t t_device_ns = 0;  ///< device clock, unwrapped, ns (origin is the device's own)
  uint32_t seq = 0;         ///< per-sensor sample number, unwrapped device counter when known
  uint16_t sensor_id = 0;   ///< index of the sensor in the rig
  uint8_t valid = 0;        ///< SampleField bits
  uint8_t flags = 0;        ///< SampleFlag bits
  Eigen::Vector3d gyr_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d acc_m_s2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d mag_uT = Eigen::Vector3d::Zero();
  /// Orientation computed on the device, sensor frame to the device's own earth frame.
  Eigen::Quaterniond q_device_sensor = Eigen::Quaterniond::Identity();

  bool has(SampleField f) const { return (valid & f) != 0; }
};

static_assert(std::is_copy_assignable_v<ImuSample>);

}  // namespace mocap
