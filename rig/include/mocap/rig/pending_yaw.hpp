// A joint hold's heading correction (hinge_heading.hpp, range_heading.hpp) on its way to the
// alignment: integrated at every sample, handed over at most every kEveryNs. A correction with
// a time constant of seconds needs no more than 10 Hz, the pace of the tracker's other heading
// alignments, and each turn republishes the calibration.
#pragma once

#include <cstdint>

namespace mocap::rig {

class PendingYaw {
 public:
  static constexpr int64_t kEveryNs = 100'000'000;

  void add(double rad) { rad_ += rad; }
  /// Whether a hand-over is due at t_ns (the next one then kEveryNs later).
  bool due(int64_t t_ns) {
    if (t_ns - handed_t_ns_ < kEveryNs) return false;
    handed_t_ns_ = t_ns;
    return true;
  }
  /// The yaw gathered since the last take, rad (it starts over).
  double take() {
    const double rad = rad_;
    rad_ = 0;
    return rad;
  }
  void reset() { *this = PendingYaw{}; }

 private:
  double rad_ = 0;
  int64_t handed_t_ns_ = 0;
};

}  // namespace mocap::rig
