// SCHED_FIFO for the calling thread (see thread_priority.hpp).
#include "mocap/core/thread_priority.hpp"

#include <pthread.h>
#include <sched.h>

#include <cerrno>
#include <cstring>

namespace mocap {

bool set_this_thread_realtime(int priority, std::string* error) {
  if (priority == 0) return true;
  if (priority < 1 || priority > kMaxRealtimePriority) {
    if (error)
      *error = "real-time priority " + std::to_string(priority) + " is outside 1.." +
               std::to_string(kMaxRealtimePriority);
    return false;
  }
  sched_param p{};
  p.sched_priority = priority;
  const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p);
  if (rc == 0) return true;
  if (error) {
    *error = std::string("cannot use real-time priority ") + std::to_string(priority) + ": " +
             std::strerror(rc);
    if (rc == EPERM)
      *error +=
          " (needs CAP_SYS_NICE or an RLIMIT_RTPRIO allowance, e.g. LimitRTPRIO= in the "
          "systemd unit)";
  }
  return false;
}

}  // namespace mocap
