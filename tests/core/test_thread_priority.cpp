// set_this_thread_realtime: range check, and either SCHED_FIFO granted or a reason naming the
// missing permission (which of the two depends on who runs the test).
#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>

#include <string>
#include <thread>

#include "mocap/core/thread_priority.hpp"

namespace mocap {
namespace {

TEST(ThreadPriority, ZeroKeepsNormalScheduling) {
  std::thread([] {
    std::string err;
    EXPECT_TRUE(set_this_thread_realtime(0, &err));
    EXPECT_EQ(sched_getscheduler(0), SCHED_OTHER);
  }).join();
}

TEST(ThreadPriority, OutOfRangeIsRefusedWithTheRange) {
  std::thread([] {
    std::string err;
    EXPECT_FALSE(set_this_thread_realtime(kMaxRealtimePriority + 1, &err));
    EXPECT_NE(err.find("outside 1..49"), std::string::npos) << err;
    EXPECT_FALSE(set_this_thread_realtime(-3, &err));
    EXPECT_EQ(sched_getscheduler(0), SCHED_OTHER);
  }).join();
}

TEST(ThreadPriority, GrantedOrExplained) {
  std::thread([] {
    std::string err;
    if (set_this_thread_realtime(5, &err)) {
      int policy = -1;
      sched_param p{};
      ASSERT_EQ(pthread_getschedparam(pthread_self(), &policy, &p), 0);
      EXPECT_EQ(policy, SCHED_FIFO);
      EXPECT_EQ(p.sched_priority, 5);
    } else {
      EXPECT_NE(err.find("cannot use real-time priority 5"), std::string::npos) << err;
      EXPECT_EQ(sched_getscheduler(0), SCHED_OTHER);
    }
  }).join();
}

}  // namespace
}  // namespace mocap
