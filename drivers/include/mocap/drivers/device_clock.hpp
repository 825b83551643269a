// Device time handling shared by every protocol: unwrapping of wrapping counters and tick clocks,
// and the drift-tracked mapping from device time to host CLOCK_MONOTONIC time.
#pragma once

#include <array>
#include <cstdint>

namespace mocap {

/// Unwraps a counter that wraps at `modulus` (e.g. 65536 for a uint16 packet counter, 2^32 for a
/// uint32 tick clock, 864000000 for a once-a-day clock). modulus 0 means "never wraps" (64-bit).
/// A step of more than half the modulus backwards is taken as the counter going backwards.
class Unwrapper {
 public:
  explicit Unwrapper(uint64_t modulus = 0) : modulus_(modulus) {}
  /// Returns the unwrapped value (the first raw value is the origin, returned as is).
  int64_t next(uint64_t raw);
  /// Signed step of the last next() call (0 on the first).
  int64_t last_step() const { return step_; }
  bool started() const { return started_; }
  void reset() { started_ = false; }

 private:
  uint64_t modulus_;
  bool started_ = false;
  uint64_t last_raw_ = 0;
  int64_t value_ = 0;
  int64_t step_ = 0;
};

/// Tracks how many samples a counter says were lost: a forward step of n > 1 means n-1 drops;
/// a zero or backward step (device restart) is reported as a reset.
struct CounterGap {
  int64_t dropped = 0;  ///< samples missing before this one
  bool reset = false;   ///< counter went backwards or jumped by more than max_step
};
CounterGap counter_gap(int64_t step, int64_t max_step);

/// Maps an unwrapped device time (ns) to host time. The host read time of a sample is its true
/// time plus a non-negative transport latency, so the lower envelope of (t_read - t_device) is
/// the clock offset. The envelope is sampled once per window (the minimum in each window) and a
/// line is fitted through the last windows, which tracks a device clock running fast or slow
/// (drift, ppm) without following the latency jitter. A device clock that jumps or restarts
/// resets the fit (reported to the caller). No allocation: fixed arrays.
class DeviceClock {
 public:
  struct Params {
    int64_t window_ns = 500'000'000;  ///< device time per envelope point
    int64_t jump_ns = 2'000'000'000;  ///< device-vs-host step mismatch that counts as a reset
  };
  DeviceClock() : DeviceClock(Params{}) {}
  explicit DeviceClock(Params p) : p_(p) {}

  /// Host time of a sample taken at device time t_device_ns and read at host time t_read_ns.
  /// `reset` is set when the mapping re-synced (first sample, or a clock jump/restart).
  int64_t map(int64_t t_device_ns, int64_t t_read_ns, bool& reset);
  /// Current drift estimate: host ns per device ns minus one (e.g. 1e-4 = device 100 ppm slow).
  double drift() const { return slope_; }
  uint64_t resets() const { return resets_; }

 private:
  static constexpr int kPoints = 16;
  void restart(int64_t t_device_ns, int64_t offset_ns);
  void refit();

  Params p_;
  bool started_ = false;
  int64_t last_device_ns_ = 0, last_read_ns_ = 0, last_out_ns_ = INT64_MIN;
  int64_t ref_device_ns_ = 0;  ///< device time origin of the fit (keeps numbers small)
  int64_t base_offset_ = 0;    ///< first offset; the fit works on offsets relative to it
  int64_t window_start_ns_ = 0;
  int64_t win_min_offset_ = 0, win_min_device_ = 0;
  std::array<int64_t, kPoints> pt_device_{}, pt_offset_{};
  int n_points_ = 0, next_point_ = 0;
  double intercept_ = 0, slope_ = 0;
  uint64_t resets_ = 0;
};

}  // namespace mocap

namespace mocap {

/// Loss detection for devices that have a clock but no sample counter: learns the nominal
/// sample period from normal steps and reports how many samples a long step skipped.
class PeriodTracker {
 public:
  /// Feeds the device-time step to this sample; returns the number of samples missing before it.
  int64_t update(int64_t step_ns);
  int64_t period_ns() const { return period_ns_; }

 private:
  int64_t period_ns_ = 0;
  int64_t candidate_ns_ = 0;
};

}  // namespace mocap
