// Output: what every consumer of pose frames is to the pipeline (the shared posture, the pose JSON
// stream, VMC, VRChat OSC, the recorder's tap, replay's file writers). One frame in; on the live
// pipeline thread it must never block: an output that does I/O hands the frame to a thread of its
// own or sends on a non-blocking socket.
#pragma once

#include "mocap/skeleton/pose_frame.hpp"

namespace mocap::outputs {

class Output {
 public:
  virtual ~Output() = default;
  /// One published frame, in order, on the pipeline's thread.
  virtual void on_frame(const PoseFrame& frame) = 0;
};

}  // namespace mocap::outputs
