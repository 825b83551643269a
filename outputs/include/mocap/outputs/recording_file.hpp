// Opening a new recording file without ever destroying data: the file is created exclusively
// (O_CREAT | O_EXCL | O_NOFOLLOW) under recording.directory, walking every directory component
// with O_NOFOLLOW so neither a symlink nor `..` leads out of it.
#pragma once

#include <ctime>
#include <string>

namespace mocap::outputs {

inline constexpr const char* kSessionExtension = "mocapses";

/// A freshly created, empty recording file.
struct RecordingFile {
  int fd = -1;       ///< open for writing (the caller owns it)
  int dir_fd = -1;   ///< its directory (the caller owns it; for unlinking a failed start)
  std::string leaf;  ///< its name inside dir_fd
  std::string path;  ///< directory + name, for messages and status
};

/// The fresh default name for a recording started at `now` (local time):
/// take-YYYYMMDD-HHMMSS.mocapses.
std::string default_take_name(std::time_t now);

/// Creates a new recording file for `name` under `directory`:
/// - `name` empty: take-YYYYMMDD-HHMMSS.mocapses, with -2, -3, ... before the extension if taken;
/// - otherwise `name` relative to `directory` (an absolute name must lie inside it); `..`
///   components, symlinks and names outside the directory are refused;
/// - an existing file is an error naming it, unless `unique` (auto_start): then the first free
///   name-N.ext is taken.
/// Throws std::runtime_error with a message naming the path on failure.
RecordingFile create_recording_file(const std::string& directory, const std::string& name,
                                    bool unique, std::time_t now);

}  // namespace mocap::outputs
