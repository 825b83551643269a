// Rotations by small angles without libm calls, for the attitude filter's per-sample path: cos x,
// sin(x)/x and atan x from their Taylor series, and a renormalisation of a quaternion that is unit
// up to rounding. Hand-written because the sincos, atan2, square roots and divisions they replace
// were a fifth of the filter's time per update (docs/filter.md, "Cost").
#pragma once

#include <Eigen/Geometry>
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

/// Largest |r| for which atan_small is used: 1/4 (14 deg; the heading innovation of single field
/// samples reaches 4-14 deg on about a quarter of BROAD's samples, so 1/16 left atan2 to them).
inline constexpr double kAtanMax = 0.25;

/// atan r for |r| <= kAtanMax: its Taylor series to r^25 (the first omitted term, r^27 / 27, is
/// below 1e-17 |r|: under a double's rounding). Estrin's scheme in r^2.
inline double atan_small(double r) {
  const double t = r * r, t2 = t * t, t4 = t2 * t2, t8 = t4 * t4;
  const double a = (1 - t * (1.0 / 3)) + t2 * (1.0 / 5 - t * (1.0 / 7));
  const double b = (1.0 / 9 - t * (1.0 / 11)) + t2 * (1.0 / 13 - t * (1.0 / 15));
  const double c = (1.0 / 17 - t * (1.0 / 19)) + t2 * (1.0 / 21 - t * (1.0 / 23));
  return r * ((a + t4 * b) + t8 * (c + t4 * (1.0 / 25)));
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
