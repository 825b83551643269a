// FrameWriterThread: an offline Output that hands frames, in order, to another Output run
// on a thread of its own (replay's BVH and pose CSV writers: formatting a frame costs as much as
// building it). Frames go over in chunks through a small bounded queue; when the writer falls
// behind, on_frame() waits: nothing is dropped, nothing reordered, so the files are the same as
// written inline. Not for the live pipeline, which must never wait (its outputs have their own
// non-blocking threads).
#pragma once

#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

#include "mocap/outputs/output.hpp"

namespace mocap::outputs {

class FrameWriterThread final : public Output {
 public:
  static constexpr std::size_t kChunk = 256;  ///< frames per hand-over
  static constexpr std::size_t kAhead = 4;    ///< chunks queued at most

  /// `target` is called on the writer thread only, until finish() returns.
  explicit FrameWriterThread(Output& target);
  ~FrameWriterThread() override;  ///< finish() (errors swallowed)
  FrameWriterThread(const FrameWriterThread&) = delete;
  FrameWriterThread& operator=(const FrameWriterThread&) = delete;

  /// Copies the frame; waits while kAhead chunks are queued.
  void on_frame(const PoseFrame& frame) override;
  /// Hands over the last frames, waits until the target has taken every frame, joins the
  /// thread; rethrows what the target threw (then later frames were not written).
  void finish();

 private:
  void run();
  void hand_over();

  Output& target_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::deque<std::vector<PoseFrame>> ready_;   // guarded by mu_
  std::vector<std::vector<PoseFrame>> spare_;  // guarded by mu_: emptied chunks for reuse
  bool closing_ = false;                       // guarded by mu_
  std::exception_ptr error_;                   // guarded by mu_
  std::vector<PoseFrame> current_;             // producer only
  std::thread thread_;
};

}  // namespace mocap::outputs
