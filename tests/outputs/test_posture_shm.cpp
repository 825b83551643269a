// Shared posture: a reader on another thread never sees a torn frame while the writer publishes
// at full speed, and readers see nothing before the first publish.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <thread>

#include "mocap/outputs/posture_shm.hpp"

namespace mocap::outputs {

TEST(PostureShm, ReaderNeverSeesTornFrames) {
  const std::string name = "/mocap-test-" + std::to_string(getpid());
  PostureWriter writer(name);
  PostureReader reader(name);
  PoseFrame f;
  EXPECT_FALSE(reader.read(f)) << "nothing published yet";

  std::atomic<bool> done{false};
  std::thread w([&] {
    PoseFrame out;
    reset_pose(out);
    for (uint64_t i = 1; i <= 20000; ++i) {
      out.frame = i;
      // Every field carries the frame number, so a mix of two frames is detectable.
      for (auto& q : out.q_earth_segment)
        q[1] = static_cast<float>(i);
      out.joint_violation_deg.back() = static_cast<float>(i);
      writer.publish(out);
    }
    done = true;
  });
  uint64_t reads = 0, last = 0;
  while (!done || reads == 0) {
    if (!reader.read(f)) continue;
    ++reads;
    ASSERT_GE(f.frame, last);
    last = f.frame;
    for (const auto& q : f.q_earth_segment)
      ASSERT_EQ(q[1], static_cast<float>(f.frame));
    ASSERT_EQ(f.joint_violation_deg.back(), static_cast<float>(f.frame));
  }
  w.join();
  ASSERT_TRUE(reader.read(f));
  EXPECT_EQ(f.frame, 20000u);
  EXPECT_GT(reads, 0u);
}

TEST(PostureShm, MissingSegmentIsAClearError) {
  try {
    PostureReader r("/mocap-does-not-exist-xyz");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no shared posture"), std::string::npos);
  }
}

}  // namespace mocap::outputs
