// The shared posture's format, both ends: the latest PoseFrame in POSIX shared memory, written
// under a seqlock by the posture output (posture_output.hpp) and read by the viewer and other
// local programs without ever blocking the writer.
//
// Layout: a header {magic, version, frame size, sequence} followed by the frame as 64-bit words.
// The writer makes the sequence odd, stores the words (relaxed atomics), makes it even again.
// A reader copies the words and retries if the sequence was odd or changed meanwhile.
#pragma once

#include <cstdint>
#include <string>

#include "mocap/skeleton/pose_frame.hpp"

namespace mocap::outputs {

/// Default shared-memory name for the current user: "/mocap-posture-<uid>".
std::string default_posture_shm_name();

class PostureWriter {
 public:
  /// Creates (or takes over) the segment, mode 0600. Throws std::runtime_error on failure.
  explicit PostureWriter(std::string name);
  ~PostureWriter();
  PostureWriter(const PostureWriter&) = delete;
  PostureWriter& operator=(const PostureWriter&) = delete;

  /// Publishes a frame. Wait-free: never blocks on readers.
  void publish(const PoseFrame& frame) noexcept;
  const std::string& name() const { return name_; }

 private:
  std::string name_;
  void* map_ = nullptr;
};

class PostureReader {
 public:
  /// Opens an existing segment read-only. Throws std::runtime_error if absent or incompatible.
  explicit PostureReader(std::string name);
  ~PostureReader();
  PostureReader(const PostureReader&) = delete;
  PostureReader& operator=(const PostureReader&) = delete;

  /// Copies the newest consistent frame. Returns false if none was published yet or the writer
  /// kept it busy for all retries (then `out` is unchanged).
  bool read(PoseFrame& out) const noexcept;
  /// Sequence number of the segment (even = stable); changes with every publish.
  uint64_t sequence() const noexcept;

 private:
  std::string name_;
  const void* map_ = nullptr;
};

}  // namespace mocap::outputs
