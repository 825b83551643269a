// Physical constants and unit factors shared by every module (one definition, so drivers,
// simulator and calibration agree on what "1 g" is).
#pragma once

#include <numbers>

namespace mocap {

/// Standard gravity (ISO 80000-3), m/s² per g: what accelerometers mean by "g".
inline constexpr double kStandardGravity_m_s2 = 9.80665;
/// Radians per degree.
inline constexpr double kRadPerDeg = std::numbers::pi / 180.0;
/// Degrees per radian.
inline constexpr double kDegPerRad = 180.0 / std::numbers::pi;

}  // namespace mocap
