// Parser of the daemon's pose JSON stream lines (schema version 1, docs/streaming.md) into a
// PoseFrame. Rejects, with a message naming the problem, anything that is not a complete,
// finite frame: a rejected line never changes the output, so NaN never reaches the avatar.
#pragma once

#include <string>
#include <string_view>

#include "mocap/skeleton/pose_frame.hpp"

namespace mocap::viewer {

/// Longest line accepted (the stream's lines are at most 16 KiB).
inline constexpr size_t kMaxPoseJsonLine = 64 * 1024;

/// Parses one line (without or with its '\n'). On success fills `out` and returns true; on
/// failure leaves `out` unchanged, sets `error` and returns false.
bool parse_pose_json(std::string_view line, PoseFrame& out, std::string& error);

}  // namespace mocap::viewer
