// The segment tree: depth-first order, names round-trip, hinge joints.
#include <gtest/gtest.h>

#include "mocap/core/segments.hpp"

namespace mocap {

TEST(Segments, ParentsPrecedeChildren) {
  EXPECT_EQ(kSegmentParent[0], kNoParent);
  for (int i = 1; i < kSegmentCount; ++i) {
    EXPECT_GE(kSegmentParent[i], 0);
    EXPECT_LT(kSegmentParent[i], i) << kSegmentNames[i];
  }
}

TEST(Segments, NamesRoundTrip) {
  for (int i = 0; i < kSegmentCount; ++i) {
    auto s = segment_from_name(kSegmentNames[i]);
    ASSERT_TRUE(s.has_value());
    EXPECT_EQ(index(*s), i);
  }
  EXPECT_FALSE(segment_from_name("tail").has_value());
}

TEST(Segments, ElbowsAndKneesAreHinges) {
  int hinges = 0;
  for (int i = 0; i < kSegmentCount; ++i)
    hinges += is_hinge(static_cast<Segment>(i));
  EXPECT_EQ(hinges, 4);
  EXPECT_TRUE(is_hinge(Segment::shank_r));
  EXPECT_FALSE(is_hinge(Segment::upper_arm_l));
}

}  // namespace mocap
