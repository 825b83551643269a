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

std::optional<TextProblem> toml_text_problem(std::string_view text) {
  if (auto bad = text_problem(text)) return bad;
  // The text is valid UTF-8 here: columns count code points (continuation bytes are skipped).
  enum class Ctx { bare, comment, basic, literal, ml_basic, ml_literal };
  Ctx ctx = Ctx::bare;
  std::size_t line = 1, col = 1;
  auto starts = [&](std::size_t i, std::string_view s) { return text.substr(i, s.size()) == s; };
  auto run_of = [&](std::size_t i, char q) {
    std::size_t n = 0;
    while (i + n < text.size() && text[i + n] == q)
      ++n;
    return n;
  };
  for (std::size_t i = 0; i < text.size();) {
    const auto b = static_cast<unsigned char>(text[i]);
    if (b == '\n') {
      // Single-line strings and comments end at the line's end (toml++ reports an unterminated
      // string itself).
      if (ctx == Ctx::comment || ctx == Ctx::basic || ctx == Ctx::literal) ctx = Ctx::bare;
      ++line;
      col = 1;
      ++i;
      continue;
    }
    if (b >= 0x80) {
      if (ctx == Ctx::bare)
        return TextProblem{line, col, "non-ASCII character outside a string or comment"};
      if ((b & 0xC0) != 0x80) ++col;  // a lead byte: one more code point
      ++i;
      continue;
    }
    std::size_t len = 1;
    switch (ctx) {
      case Ctx::bare:
        if (b == '#') {
          ctx = Ctx::comment;
        } else if (starts(i, "\"\"\"")) {
          ctx = Ctx::ml_basic;
          len = 3;
        } else if (starts(i, "'''")) {
          ctx = Ctx::ml_literal;
          len = 3;
        } else if (b == '"') {
          ctx = Ctx::basic;
        } else if (b == '\'') {
          ctx = Ctx::literal;
        }
        break;
      case Ctx::comment:
        break;
      case Ctx::basic:
        if (b == '\\' && i + 1 < text.size() && text[i + 1] != '\n')
          len = 2;  // an escaped character (an escaped non-ASCII byte is an error for toml++)
        else if (b == '"')
          ctx = Ctx::bare;
        break;
      case Ctx::literal:
        if (b == '\'') ctx = Ctx::bare;
        break;
      case Ctx::ml_basic:
      case Ctx::ml_literal: {
        const char q = ctx == Ctx::ml_basic ? '"' : '\'';
        if (ctx == Ctx::ml_basic && b == '\\' && i + 1 < text.size() && text[i + 1] != '\n' &&
            static_cast<unsigned char>(text[i + 1]) < 0x80) {
          len = 2;
        } else if (b == static_cast<unsigned char>(q)) {
          // The closing delimiter is the last three quotes of a run of three to five.
          const std::size_t n = run_of(i, q);
          if (n >= 3) {
            len = n < 5 ? n : 5;
            ctx = Ctx::bare;
          } else {
            len = n;
          }
        }
        break;
      }
    }
    i += len;
    col += len;
  }
  return std::nullopt;
}

}  // namespace mocap
