// The pose JSON stream's line format (schema in docs/streaming.md): one frame as one line of
// JSON. Written by the JSON stream output and by `mocap export --json`.
#pragma once

#include <cstddef>

#include "mocap/skeleton/pose_frame.hpp"

namespace mocap::outputs {

/// Longest line format_pose_json() can produce (a full rig of 32 sensors fits with room).
inline constexpr std::size_t kPoseJsonMaxLine = 16 * 1024;
/// Schema version written as "v" in every line.
inline constexpr int kPoseJsonVersion = 1;

/// Formats one frame as a JSON line ending in '\n' into out[0..capacity). Returns the number of
/// bytes written, or 0 if it does not fit. Allocates nothing. Non-finite numbers become null.
std::size_t format_pose_json(const PoseFrame& frame, char* out, std::size_t capacity) noexcept;

}  // namespace mocap::outputs
