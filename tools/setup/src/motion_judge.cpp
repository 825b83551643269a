// Which sensor moved alone (see motion_judge.hpp).
#include "mocap/setup/motion_judge.hpp"

namespace mocap::setup {

void MotionJudge::reset() {
  streak_sensor_ = -1;
  streak_ = ambiguous_streak_ = 0;
  winner_ = second_ = -1;
}

bool MotionJudge::still(const std::vector<double>& speed, const std::vector<bool>& free) const {
  for (std::size_t i = 0; i < speed.size() && i < free.size(); ++i)
    if (free[i] && speed[i] > p_.threshold_rad_s) return false;
  return true;
}

MotionJudge::Verdict MotionJudge::judge(const std::vector<double>& speed,
                                        const std::vector<bool>& free) {
  int top = -1, next = -1;
  for (std::size_t i = 0; i < speed.size() && i < free.size(); ++i) {
    if (!free[i]) continue;
    const int k = static_cast<int>(i);
    if (top < 0 || speed[i] > speed[top]) {
      next = top;
      top = k;
    } else if (next < 0 || speed[i] > speed[next]) {
      next = k;
    }
  }
  if (top < 0 || speed[top] <= p_.threshold_rad_s) {  // nothing moves
    streak_sensor_ = -1;
    streak_ = ambiguous_streak_ = 0;
    return Verdict::waiting;
  }
  const bool alone =
      next < 0 || speed[next] <= p_.threshold_rad_s || speed[top] >= p_.dominance * speed[next];
  if (!alone) {
    streak_sensor_ = -1;
    streak_ = 0;
    if (++ambiguous_streak_ < p_.ambiguous_windows) return Verdict::waiting;
    winner_ = top;
    second_ = next;
    ambiguous_streak_ = 0;
    return Verdict::ambiguous;
  }
  ambiguous_streak_ = 0;
  streak_ = top == streak_sensor_ ? streak_ + 1 : 1;
  streak_sensor_ = top;
  if (streak_ < p_.hold_windows) return Verdict::waiting;
  winner_ = top;
  second_ = -1;
  streak_ = 0;
  return Verdict::assigned;
}

}  // namespace mocap::setup
