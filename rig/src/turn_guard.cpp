// TurnGuard: a running estimate's far answers refused, or a wrong first answer corrected (see
// turn_guard.hpp).
#include "mocap/rig/turn_guard.hpp"

#include <algorithm>
#include <cmath>

#include "mocap/core/units.hpp"
#include "mocap/rig/alignment.hpp"
#include "mocap/skeleton/quat_math.hpp"

namespace mocap::rig {

TurnGuard::Verdict TurnGuard::judge(int s, const Facing& held, const Facing& candidate) {
  if (s < 0 || s >= kSegmentCount || !candidate.known()) return Verdict::refuse;
  State& st = state_[static_cast<size_t>(s)];
  constexpr double kFarRad = Alignment::kImplausibleTurnDeg * kRadPerDeg;
  if (held.source != candidate.source) {  // another source's facing: replaces() decides
    st = State{1, 0, 0};
    return Verdict::follow;
  }
  if (std::abs(wrap_angle_rad(candidate.yaw_rad - held.yaw_rad)) <= kFarRad) {
    ++st.held_solves;
    st.contrary_solves = 0;
    return Verdict::follow;
  }
  const bool agrees = st.contrary_solves > 0 &&
                      std::abs(wrap_angle_rad(candidate.yaw_rad - st.contrary_yaw_rad)) <= kFarRad;
  st.contrary_solves = agrees ? st.contrary_solves + 1 : 1;
  st.contrary_yaw_rad = candidate.yaw_rad;
  if (st.contrary_solves <= std::max(kMinContrarySolves, st.held_solves)) return Verdict::refuse;
  st = State{st.contrary_solves, 0, 0};
  return Verdict::correct;
}

}  // namespace mocap::rig
