// TextLines: line reading through zlib's gzread (transparent for plain files).
#include "mocap/daemon/text_lines.hpp"

#include <zlib.h>

#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace mocap::daemon {

TextLines::TextLines(const std::string& path) : path_(path) {
  gzFile f = gzopen(path.c_str(), "rb");
  if (!f) throw std::runtime_error(path + ": cannot open");
  gzbuffer(f, 1 << 16);
  gz_ = f;
  std::error_code ec;
  const auto n = std::filesystem::file_size(path, ec);
  if (!ec && n > 0) size_ = n;
}

TextLines::~TextLines() {
  if (gz_) gzclose(static_cast<gzFile>(gz_));
}

bool TextLines::next(std::string& line) {
  line.clear();
  if (!error_.empty()) return false;
  gzFile f = static_cast<gzFile>(gz_);
  bool any = false;
  for (;;) {
    const int c = gzgetc(f);
    if (c < 0) {
      int errnum = 0;
      const char* msg = gzerror(f, &errnum);
      if (errnum != Z_OK && errnum != Z_STREAM_END) {
        error_ = path_ + ": read error: " + (msg ? msg : "?");
        return false;
      }
      return any;
    }
    any = true;
    if (c == '\n') return true;
    line.push_back(static_cast<char>(c));
  }
}

uint64_t TextLines::file_offset() const {
  const z_off_t o = gzoffset(static_cast<gzFile>(gz_));
  return o > 0 ? static_cast<uint64_t>(o) : 0;
}

}  // namespace mocap::daemon
