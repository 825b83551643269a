// Whether a running estimate's new facing for a segment may turn the facing it found before.
//
// A running estimate (a knee's axis from the two segments' tilt, hinge_axis.hpp) answers every
// second. An answer within Alignment::kImplausibleTurnDeg of the held facing of the same source
// is followed and confirms it (the held facing's tenure grows by one). An answer further off is
// refused and reported: a segment never flips on a stretch of odd motion (the hinge's signs
// chosen the other way, a drifting rate integral). But the held facing may itself be the wrong
// one: the first answers come from a few seconds of motion (CMU 01_12 seed 3, the first
// answer from half the shipped tilt evidence: the right thigh's facing walked -177 -> -151 deg
// in four solves, then every answer for the rest of the clip was 152 deg, refused: +34.8 deg).
// So far answers that agree with each other (within kImplausibleTurnDeg of the previous one)
// for longer than the held facing was ever confirmed, and at least kMinContrarySolves in a row,
// replace it: a correction, reported as such. A facing confirmed for minutes needs the contrary
// answers for as long (a flip would have to persist that long), a first answer confirmed for a
// few seconds is corrected after kMinContrarySolves.
#pragma once

#include <array>
#include <cstdint>

#include "mocap/core/segments.hpp"
#include "mocap/rig/facing.hpp"

namespace mocap::rig {

class TurnGuard {
 public:
  static constexpr int kMinContrarySolves = 5;
  enum class Verdict : uint8_t { follow, refuse, correct };

  /// The verdict on `candidate` for segment s while `held` is its facing.
  Verdict judge(int s, const Facing& held, const Facing& candidate);
  /// Forgets every segment's tenure (a new calibration).
  void reset() { state_ = {}; }

 private:
  struct State {
    int held_solves = 0;      ///< answers of the held facing's source that agreed with it
    int contrary_solves = 0;  ///< far answers in a row agreeing with each other
    double contrary_yaw_rad = 0;
  };
  std::array<State, kSegmentCount> state_{};
};

}  // namespace mocap::rig
