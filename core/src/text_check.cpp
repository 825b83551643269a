// NUL and UTF-8 validation of configuration text.
#include "mocap/core/text_check.hpp"

#include <cstdint>

namespace mocap {

std::optional<TextProblem> text_problem(std::string_view text, bool ascii_only) {
  std::size_t line = 1, col = 1;
  auto where = [&](const char* what) { return TextProblem{line, col, what}; };
  for (std::size_t i = 0; i < text.size();) {
    const auto b = static_cast<uint8_t>(text[i]);
    if (b == 0) return where("NUL byte");
    if (b < 0x80) {
      if (b == '\n') {
        ++line;
        col = 1;
      } else {
        ++col;
      }
      ++i;
      continue;
    }
    if (ascii_only) return where("non-ASCII character (TOML files here must be ASCII)");
    int len = 0;
    uint32_t cp = 0;
    if ((b & 0xE0) == 0xC0) {
      len = 2;
      cp = b & 0x1F;
    } else if ((b & 0xF0) == 0xE0) {
      len = 3;
      cp = b & 0x0F;
    } else if ((b & 0xF8) == 0xF0) {
      len = 4;
      cp = b & 0x07;
    } else {
      return where("invalid UTF-8 lead byte");
    }
    if (i + len > text.size()) return where("truncated UTF-8 sequence");
    for (int k = 1; k < len; ++k) {
      const auto c = static_cast<uint8_t>(text[i + k]);
      if ((c & 0xC0) != 0x80) return where("invalid UTF-8 continuation byte");
      cp = (cp << 6) | (c & 0x3F);
    }
    static constexpr uint32_t kMin[5] = {0, 0, 0x80, 0x800, 0x10000};
    if (cp < kMin[len]) return where("overlong UTF-8 sequence");
    if (cp >= 0xD800 && cp <= 0xDFFF) return where("UTF-8 encoded surrogate");
    if (cp > 0x10FFFF) return where("UTF-8 code point beyond U+10FFFF");
    i += len;
    ++col;
  }
  return std::nullopt;
}

}  // namespace mocap
