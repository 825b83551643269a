// Monotonic host time in nanoseconds, the clock every timestamp in the system is expressed in.
#pragma once

#include <cstdint>

namespace mocap {

/// CLOCK_MONOTONIC now, in ns.
int64_t monotonic_ns();
/// CLOCK_REALTIME in ns since 1970-01-01 UTC (wall clock: may step; never for intervals).
int64_t realtime_ns();

/// Seconds to ns and back (double).
constexpr int64_t s_to_ns(double s) {
  return static_cast<int64_t>(s * 1e9);
}
constexpr double ns_to_s(int64_t ns) {
  return static_cast<double>(ns) * 1e-9;
}

}  // namespace mocap
