// Lines of a text file that may be gzip-compressed (zlib reads plain files as they are): the
// sample CSVs `mocap replay`, `mocapd --replay` and `mocap stills` read may be `.csv.gz`.
#pragma once

#include <cstdint>
#include <string>

namespace mocap::daemon {

class TextLines {
 public:
  /// Opens `path` (plain or gzip); throws std::runtime_error naming the file if it cannot.
  explicit TextLines(const std::string& path);
  ~TextLines();
  TextLines(const TextLines&) = delete;
  TextLines& operator=(const TextLines&) = delete;

  /// The next line without its '\n' (false at the end or on a read error: see error()).
  bool next(std::string& line);
  /// Bytes of the file read so far (compressed bytes for a gzip file), for progress.
  uint64_t file_offset() const;
  /// The file's size in bytes (at least 1).
  uint64_t file_size() const { return size_; }
  /// Empty unless reading failed (a corrupt or truncated gzip stream).
  const std::string& error() const { return error_; }

 private:
  std::string path_, error_;
  void* gz_ = nullptr;  // gzFile (zlib.h stays out of this header)
  uint64_t size_ = 1;
};

}  // namespace mocap::daemon
