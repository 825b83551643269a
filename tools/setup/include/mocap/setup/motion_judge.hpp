// Which sensor moved, for one prompt of `mocap setup` ("wave your left hand"): fed one window of
// every sensor's angular speed at a time (MotionMeter), it names the sensor that moved alone, or
// says two moved at once. Pure: no clock, no I/O (tests/setup/test_motion_judge.cpp).
//   moving: a free (not yet assigned) sensor whose mean speed is above `threshold_rad_s`;
//   alone:  the fastest moving sensor, `dominance` times faster than every other free one
//           (a hand's wave shakes the forearm a little: that does not count);
//   assigned once the same sensor moved alone for `hold_windows` windows in a row;
//   ambiguous once two or more moved comparably for `ambiguous_windows` windows in a row.
// Assigned sensors are not free: the prompts go from the hands and feet inwards, so moving an
// elbow (forearm and hand turn alike) finds the forearm once the hand has its sensor.
#pragma once

#include <vector>

namespace mocap::setup {

struct JudgeParams {
  double threshold_rad_s = 1.0;  ///< about 57 deg/s on average over a window
  double dominance = 3.0;
  int hold_windows = 3;
  int ambiguous_windows = 2;
};

class MotionJudge {
 public:
  enum class Verdict { waiting, assigned, ambiguous };

  explicit MotionJudge(JudgeParams p = {}) : p_(p) {}
  /// One window: speed[i] of sensor i, free[i] whether it may still be assigned.
  Verdict judge(const std::vector<double>& speed, const std::vector<bool>& free);
  /// After `assigned`: the sensor. After `ambiguous`: the two fastest (first, second).
  int winner() const { return winner_; }
  int second() const { return second_; }
  /// True when no free sensor moves (above the threshold) in this window.
  bool still(const std::vector<double>& speed, const std::vector<bool>& free) const;
  /// Forgets the streaks (a new prompt, or the same one asked again).
  void reset();
  const JudgeParams& params() const { return p_; }

 private:
  JudgeParams p_;
  int streak_sensor_ = -1, streak_ = 0, ambiguous_streak_ = 0;
  int winner_ = -1, second_ = -1;
};

}  // namespace mocap::setup
