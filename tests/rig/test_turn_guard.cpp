// The guard on a running estimate's far answers (rig/turn_guard.hpp): a flip of a facing
// confirmed for long is refused however long it lasts; a wrong first answer confirmed for a few
// solves is corrected once far answers agree for longer; far answers that disagree with each
// other never correct anything; another source's facing is replaces()' business.
#include <gtest/gtest.h>

#include "mocap/core/segments.hpp"
#include "mocap/core/units.hpp"
#include "mocap/rig/turn_guard.hpp"

namespace mocap::rig {
namespace {

constexpr int kThigh = static_cast<int>(Segment::thigh_r);

Facing hinge(double yaw_deg) {
  return Facing{yaw_deg * kRadPerDeg, 5.0, AlignSource::hinge_axis};
}

/// Feeds `n` answers of yaw_deg against `held` (updated when followed or corrected); returns
/// the verdicts' counts {follow, refuse, correct}.
std::array<int, 3> feed(TurnGuard& g, Facing& held, double yaw_deg, int n) {
  std::array<int, 3> count{};
  for (int k = 0; k < n; ++k) {
    const TurnGuard::Verdict v = g.judge(kThigh, held, hinge(yaw_deg));
    ++count[static_cast<size_t>(v)];
    if (v != TurnGuard::Verdict::refuse) held = hinge(yaw_deg);
  }
  return count;
}

TEST(TurnGuard, AFlipOfALongConfirmedFacingIsRefusedForAsLongAsItWasConfirmed) {
  TurnGuard g;
  Facing held{0.0, 8.0, AlignSource::site_normal};
  EXPECT_EQ(feed(g, held, 10, 1)[0], 1);  // the first answer replaces the site prior
  feed(g, held, 12, 60);                  // confirmed for a minute
  // The signs chosen the other way for 50 s: refused throughout, the facing held.
  const auto c = feed(g, held, -168, 50);
  EXPECT_EQ(c[1], 50);
  EXPECT_NEAR(held.yaw_rad * kDegPerRad, 12, 1e-9);
  // Back to the right signs: followed, and the flip's run is forgotten.
  EXPECT_EQ(feed(g, held, 13, 1)[0], 1);
  EXPECT_EQ(feed(g, held, -168, 30)[2], 0);
}

TEST(TurnGuard, AWrongFirstAnswerIsCorrectedOnceFarAnswersAgreeLonger) {
  TurnGuard g;
  Facing held{0.0, 8.0, AlignSource::site_normal};
  // CMU 01_12 seed 3 at half the tilt evidence: the first answers walk, then settle far off.
  for (double yaw : {-177.0, -168.0, -160.0, -151.0})
    feed(g, held, yaw, 1);
  const auto before = feed(g, held, 152, TurnGuard::kMinContrarySolves);
  EXPECT_EQ(before[1], TurnGuard::kMinContrarySolves);  // refused while not yet sure
  const auto after = feed(g, held, 152, 1);
  EXPECT_EQ(after[2], 1);  // then corrected
  EXPECT_NEAR(held.yaw_rad * kDegPerRad, 152, 1e-9);
  // The correction is the held facing now, with the far answers' tenure: a flip back is
  // refused again.
  EXPECT_EQ(feed(g, held, -151, TurnGuard::kMinContrarySolves + 1)[1],
            TurnGuard::kMinContrarySolves + 1);
}

TEST(TurnGuard, FarAnswersThatDisagreeWithEachOtherNeverCorrect) {
  TurnGuard g;
  Facing held{0.0, 8.0, AlignSource::site_normal};
  feed(g, held, 0, 2);
  for (int k = 0; k < 40; ++k)  // odd motion: answers 90 deg apart each solve
    EXPECT_EQ(feed(g, held, k % 2 ? 90 : 180, 1)[1], 1);
  EXPECT_NEAR(held.yaw_rad, 0, 1e-9);
}

TEST(TurnGuard, AnotherSourcesFacingIsFollowedAndStartsTheTenureOver) {
  TurnGuard g;
  Facing held = hinge(0);
  feed(g, held, 0, 100);
  // The mounting motion's facing, far off: another source (replaces() weighs it).
  const Facing motion{170 * kRadPerDeg, 3.0, AlignSource::motion};
  EXPECT_EQ(g.judge(kThigh, held, motion), TurnGuard::Verdict::follow);
  held = motion;
  // Another source's facing is not this guard's to judge (replaces() weighs it) ...
  EXPECT_EQ(g.judge(kThigh, held, hinge(0)), TurnGuard::Verdict::follow);
  // ... and where the hinge's answer then replaces it, its tenure starts over: far answers
  // agreeing with each other correct it after kMinContrarySolves, not after 100.
  held = hinge(172);
  const auto c = feed(g, held, 0, TurnGuard::kMinContrarySolves + 1);
  EXPECT_EQ(c[1], TurnGuard::kMinContrarySolves);
  EXPECT_EQ(c[2], 1);
  // A reset (a new calibration) forgets every tenure.
  g.reset();
  held = hinge(0);
  EXPECT_EQ(g.judge(kThigh, held, hinge(90)), TurnGuard::Verdict::refuse);
}

}  // namespace
}  // namespace mocap::rig
