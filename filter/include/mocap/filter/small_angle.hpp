// Rotations by small angles without libm calls, for the attitude filter's per-sample path: cos x,
// sin(x)/x and atan x from their Taylor series, atan2 near a known angle (the field's dip) from a
// grid of anchors, and a renormalisation of a quaternion that is unit up to rounding.
// Hand-written because the sincos, atan2, asin, square roots and divisions they replace were a
// fifth of the filter's time per update (docs/filter.md, "Cost").
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cmath>

namespace mocap {

/// Largest x^2 for which cos_small / sinc_small are used: |x| <= 1/16 rad (3.6 deg; a gyro
/// sample's half-angle at 100 Hz and 12 rad/s). The first omitted terms, x^10/10! and x^10/11!,
/// are below 3e-19: under a double's rounding, so the values are libm's within an ulp.
inline constexpr double kSmallAngle2 = 1.0 / 256;

/// cos x for x^2 = x2 <= kSmallAngle2. (Evaluated as pairs of terms, Estrin's scheme: half the
/// dependent operations of Horner's, on the filter's critical path.)
inline double cos_small(double x2) {
  const double x4 = x2 * x2;
  return (1 - 0.5 * x2) + x4 * ((1.0 / 24 - x2 * (1.0 / 720)) + x4 * (1.0 / 40320));
}

/// sin(x) / x for x^2 = x2 <= kSmallAngle2.
inline double sinc_small(double x2) {
  const double x4 = x2 * x2;
  return (1 - x2 * (1.0 / 6)) + x4 * ((1.0 / 120 - x2 * (1.0 / 5040)) + x4 * (1.0 / 362880));
}

/// atan r for r^2 <= kSmallAngle2 (|r| <= 1/16: the first omitted term, r^15 / 15, is below
/// 1e-18 |r|).
inline double atan_small(double r) {
  const double r2 = r * r, r4 = r2 * r2, r8 = r4 * r4;
  const double lo = (1 - r2 * (1.0 / 3)) + r4 * (1.0 / 5 - r2 * (1.0 / 7));
  const double hi = (1.0 / 9 - r2 * (1.0 / 11)) + r4 * (1.0 / 13);
  return r * (lo + r8 * hi);
}

/// Largest |r| for which atan_quarter is used: 1/4 (14 deg; the heading innovation of single field
/// samples reaches 4-14 deg on about a quarter of BROAD's samples, so 1/16 left atan2 to them).
inline constexpr double kAtanQuarterMax = 0.25;

/// atan r for |r| <= kAtanQuarterMax: its Taylor series to r^25 (the first omitted term, r^27 /
/// 27, is below 1e-17 |r|: under a double's rounding). Estrin's scheme in r^2.
inline double atan_quarter(double r) {
  const double t = r * r, t2 = t * t, t4 = t2 * t2, t8 = t4 * t4;
  const double a = (1 - t * (1.0 / 3)) + t2 * (1.0 / 5 - t * (1.0 / 7));
  const double b = (1.0 / 9 - t * (1.0 / 11)) + t2 * (1.0 / 13 - t * (1.0 / 15));
  const double c = (1.0 / 17 - t * (1.0 / 19)) + t2 * (1.0 / 21 - t * (1.0 / 23));
  return r * ((a + t4 * b) + t8 * (c + t4 * (1.0 / 25)));
}

/// sin and cos of the anchors k / 64 rad, k = -kAngleGridHalf..kAngleGridHalf (|k / 64| < pi / 2),
/// for atan2_near: Taylor series in long double at compile time, then rounded to double.
inline constexpr int kAngleGridHalf = 100;
struct AngleGridEntry {
  double sin, cos;
};
namespace detail {
constexpr long double sin_series(long double x) {
  long double term = x, sum = x;
  for (int n = 1; n < 30; ++n) {
    term *= -x * x / ((2 * n) * (2 * n + 1));
    sum += term;
  }
  return sum;
}
constexpr long double cos_series(long double x) {
  long double term = 1, sum = 1;
  for (int n = 1; n < 30; ++n) {
    term *= -x * x / ((2 * n - 1) * (2 * n));
    sum += term;
  }
  return sum;
}
constexpr std::array<AngleGridEntry, 2 * kAngleGridHalf + 1> make_angle_grid() {
  std::array<AngleGridEntry, 2 * kAngleGridHalf + 1> g{};
  for (int k = -kAngleGridHalf; k <= kAngleGridHalf; ++k) {
    const long double x = k / 64.0L;
    g[k + kAngleGridHalf] = {static_cast<double>(sin_series(x)),
                             static_cast<double>(cos_series(x))};
  }
  return g;
}
}  // namespace detail
inline constexpr std::array<AngleGridEntry, 2 * kAngleGridHalf + 1> kAngleGrid =
    detail::make_angle_grid();

/// atan2(y, x) for a direction near the angle near_rad (|near_rad| < pi / 2): the grid anchor a
/// nearest to it (within 1/128 rad) plus atan_small of the direction turned back by a. False
/// (angle untouched) when the direction is more than atan(1/16) from a (so it is taken whenever
/// it is within atan(1/16) - 1/128, about 3.1 deg, of near_rad), or near_rad is off the grid or
/// NaN.
inline bool atan2_near(double y, double x, double near_rad, double& angle) {
  const double i_d = near_rad * 64 + (kAngleGridHalf + 0.5);  // the index, rounded when truncated
  if (!(i_d >= 0 && i_d < 2 * kAngleGridHalf + 1)) return false;
  const int i = static_cast<int>(i_d), k = i - kAngleGridHalf;
  const AngleGridEntry& a = kAngleGrid[i];
  const double along = x * a.cos + y * a.sin, across = y * a.cos - x * a.sin;
  if (!(along > 0 && std::abs(across) * 16 <= along)) return false;
  angle = static_cast<double>(k) * (1.0 / 64) + atan_small(across / along);
  return true;
}

/// q / |q| for a quaternion whose norm is 1 up to rounding of a few operations (a product of unit
/// quaternions): one Newton step of 1/sqrt(|q|^2) at 1, no square root or division; exact
/// normalisation when the norm is further off.
inline void renormalize(Eigen::Quaterniond& q) {
  const double n2 = q.squaredNorm();
  const double d = n2 - 1;
  if (std::abs(d) < 1e-8)
    q.coeffs() *= 1.5 - 0.5 * n2;  // the norm is then 1 - 3 d^2 / 8
  else
    q.normalize();
}

}  // namespace mocap
