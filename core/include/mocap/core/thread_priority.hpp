// Real-time scheduling for the threads on a sample's path (device readers, pipeline, pose
// stream): with SCHED_FIFO they preempt ordinary work, so a busy machine does not add
// scheduling delay to the latency. Needs CAP_SYS_NICE or an RLIMIT_RTPRIO allowance (root,
// `LimitRTPRIO=` in a systemd unit, or rtkit); without it the thread keeps normal scheduling.
#pragma once

#include <string>

namespace mocap {

/// Highest priority accepted by the configuration (SCHED_FIFO allows 1..99; keep below the
/// kernel's own threads at 50).
inline constexpr int kMaxRealtimePriority = 49;

/// Puts the calling thread in SCHED_FIFO at `priority` (1..kMaxRealtimePriority); 0 does nothing
/// and succeeds. Returns false with a reason naming the missing permission otherwise.
bool set_this_thread_realtime(int priority, std::string* error);

}  // namespace mocap
