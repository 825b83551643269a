// Counter unwrapping and the drift-tracked device-to-host time mapping (see device_clock.hpp).
#include "mocap/drivers/device_clock.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace mocap {

int64_t Unwrapper::next(uint64_t raw) {
  if (!started_) {
    started_ = true;
    last_raw_ = modulus_ ? raw % modulus_ : raw;
    value_ = static_cast<int64_t>(last_raw_);
    step_ = 0;
    return value_;
  }
  if (modulus_ == 0) {
    step_ = static_cast<int64_t>(raw - last_raw_);
    last_raw_ = raw;
  } else {
    raw %= modulus_;
    // (raw - last) mod modulus without overflow (modulus may be up to 2^63).
    const uint64_t fwd = raw >= last_raw_ ? raw - last_raw_ : modulus_ - (last_raw_ - raw);
    step_ = fwd > modulus_ / 2 ? -static_cast<int64_t>(modulus_ - fwd) : static_cast<int64_t>(fwd);
    last_raw_ = raw;
  }
  value_ = static_cast<int64_t>(static_cast<uint64_t>(value_) + static_cast<uint64_t>(step_));
  return value_;
}

CounterGap counter_gap(int64_t step, int64_t max_step) {
  CounterGap g;
  if (step <= 0 || step > max_step) {
    g.reset = true;
  } else {
    g.dropped = step - 1;
  }
  return g;
}

void DeviceClock::restart(int64_t t_device_ns, int64_t offset_ns) {
  started_ = true;
  ref_device_ns_ = t_device_ns;
  base_offset_ = offset_ns;
  window_start_ns_ = t_device_ns;
  win_min_offset_ = 0;
  win_min_device_ = t_device_ns;
  n_points_ = next_point_ = 0;
  intercept_ = slope_ = 0;
}

void DeviceClock::refit() {
  // Least squares through the completed envelope points (plus the open window while fewer than
  // two are complete).
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  auto add = [&](int64_t d, int64_t o) {
    const double x = static_cast<double>(d - ref_device_ns_) * 1e-9;
    const double y = static_cast<double>(o);
    sx += x, sy += y, sxx += x * x, sxy += x * y, ++n;
  };
  for (int i = 0; i < n_points_; ++i)
    add(pt_device_[i], pt_offset_[i]);
  if (n_points_ < 2) add(win_min_device_, win_min_offset_);
  const double det = n * sxx - sx * sx;
  if (n >= 2 && det > 1e-12) {
    slope_ = std::clamp((n * sxy - sx * sy) / det * 1e-9, -1e-3, 1e-3);  // ns per ns
    intercept_ = (sy - slope_ * 1e9 * sx) / n;
  } else {
    slope_ = 0;
    intercept_ = sy / n;
  }
}

int64_t DeviceClock::map(int64_t t_device_ns, int64_t t_read_ns, bool& reset) {
  reset = false;
  if (started_) {
    // Differences in unsigned arithmetic: adversarial device times must not overflow.
    const auto diff = [](int64_t a, int64_t b) {
      return static_cast<int64_t>(static_cast<uint64_t>(a) - static_cast<uint64_t>(b));
    };
    const int64_t dd = diff(t_device_ns, last_device_ns_), dh = diff(t_read_ns, last_read_ns_);
    const int64_t mismatch = diff(dd, dh);
    if (dd < -1'000'000 || mismatch > p_.jump_ns || mismatch < -p_.jump_ns) {
      reset = true;
      ++resets_;
      started_ = false;
    }
  }
  if (!started_) restart(t_device_ns, t_read_ns - t_device_ns);
  last_device_ns_ = t_device_ns;
  last_read_ns_ = t_read_ns;

  const int64_t offset = t_read_ns - t_device_ns - base_offset_;
  if (offset < win_min_offset_ || t_device_ns == window_start_ns_) {
    win_min_offset_ = offset;
    win_min_device_ = t_device_ns;
  }
  if (t_device_ns - window_start_ns_ >= p_.window_ns) {
    pt_device_[next_point_] = win_min_device_;
    pt_offset_[next_point_] = win_min_offset_;
    next_point_ = (next_point_ + 1) % kPoints;
    n_points_ = std::min(n_points_ + 1, kPoints);
    window_start_ns_ = t_device_ns;
    win_min_offset_ = offset;
    win_min_device_ = t_device_ns;
  }
  refit();
  const double rel = static_cast<double>(t_device_ns - ref_device_ns_);
  int64_t out = t_device_ns + base_offset_ + static_cast<int64_t>(intercept_ + slope_ * rel);
  out = std::min(out, t_read_ns);  // a sample cannot be measured after it was read
  out = std::max(out, last_out_ns_);
  last_out_ns_ = out;
  return out;
}

}  // namespace mocap

namespace mocap {

int64_t PeriodTracker::update(int64_t step_ns) {
  if (step_ns <= 0) return 0;
  if (period_ns_ == 0) {
    // Two similar consecutive steps establish the period.
    if (candidate_ns_ > 0 && std::fabs(static_cast<double>(step_ns) / candidate_ns_ - 1.0) < 0.25)
      period_ns_ = candidate_ns_ / 2 + step_ns / 2;
    candidate_ns_ = step_ns;
    return 0;
  }
  const double ratio = static_cast<double>(step_ns) / static_cast<double>(period_ns_);
  if (ratio < 1.5) {
    if (ratio > 0.5) period_ns_ += (step_ns - period_ns_) / 16;  // slow tracking
    return 0;
  }
  return ratio > 1e12 ? int64_t{1'000'000'000'000} : std::llround(ratio) - 1;
}

}  // namespace mocap
