// Second-order Butterworth low-pass for N channels with a mean-of-first-tau start-up, the
// building block of the attitude filter's slow paths. Plain data so filter state can be saved.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <numbers>

#include "mocap/core/units.hpp"

namespace mocap {

/// Biquad coefficients (direct form II transposed). Pass-through when tau <= 0 or the cut-off
/// is too close to Nyquist to be realised.
struct LowpassCoeffs {
  double b0 = 1, b1 = 0, b2 = 0, a1 = 0, a2 = 0;
  bool pass = true;
};

/// Butterworth with cut-off f_c = sqrt(2) / (2 pi tau_s), sampled every ts_s.
inline LowpassCoeffs butterworth(double tau_s, double ts_s) {
  LowpassCoeffs c;
  if (!(tau_s > 0) || !(ts_s > 0)) return c;
  const double fc_hz = std::sqrt(2.0) / (2.0 * std::numbers::pi * tau_s);
  if (fc_hz * ts_s >= 0.45) return c;  // near Nyquist: behave as pass-through
  const double k = std::tan(std::numbers::pi * fc_hz * ts_s);
  const double d = k * k + std::sqrt(2.0) * k + 1.0;
  c.b0 = k * k / d;
  c.b1 = 2.0 * c.b0;
  c.b2 = c.b0;
  c.a1 = 2.0 * (k * k - 1.0) / d;
  c.a2 = (1.0 - std::sqrt(2.0) * k + k * k) / d;
  c.pass = false;
  return c;
}

/// First-order gain for a time constant: 1 - exp(-ts/tau); 1 when tau == 0, 0 when tau < 0.
inline double gain_from_tau(double tau_s, double ts_s) {
  if (tau_s < 0) return 0.0;
  if (tau_s == 0) return 1.0;
  return 1.0 - std::exp(-ts_s / tau_s);
}

/// N-channel Butterworth state. Until tau_s of input has been seen the output is the running
/// mean, and the filter then starts in steady state at that mean (no start-up transient).
template <int N>
struct Lowpass {
  std::array<double, N> s0{}, s1{}, out{};
  double init_t_s = 0;  ///< time accumulated during start-up; < 0 once running
  int init_n = 0;

  void reset() { *this = Lowpass{}; }

  /// Running in steady state at x (as if x had been the input for ever).
  void set_steady(const double* x, const LowpassCoeffs& c) {
    init_t_s = -1;
    for (int i = 0; i < N; ++i) {
      out[i] = x[i];
      s0[i] = x[i] * (1.0 - c.b0);
      s1[i] = x[i] * (c.b2 - c.a2);
    }
  }

  const std::array<double, N>& step(const double* x, const LowpassCoeffs& c, double tau_s,
                                    double ts_s) {
    if (c.pass) {
      for (int i = 0; i < N; ++i)
        out[i] = x[i];
      return out;
    }
    if (init_t_s >= 0) {
      ++init_n;
      for (int i = 0; i < N; ++i) {
        s0[i] += x[i];  // running sum during start-up
        out[i] = s0[i] / init_n;
      }
      init_t_s += ts_s;
      if (init_t_s >= tau_s) set_steady(out.data(), c);
      return out;
    }
    // Channel-wise, as Eigen arrays: the same operations per channel, two channels per SIMD
    // instruction (the per-sample path runs a dozen channels).
    using Channels = Eigen::Array<double, N, 1>;
    const Eigen::Map<const Channels> xs(x);
    Eigen::Map<Channels> y(out.data()), z0(s0.data()), z1(s1.data());
    y = c.b0 * xs + z0;
    z0 = c.b1 * xs - c.a1 * y + z1;
    z1 = c.b2 * xs - c.a2 * y;
    return out;
  }
};

}  // namespace mocap
