// NUL and UTF-8 validation of configuration text.
#include "mocap/core/text_check.hpp"

#include <cstdint>
#include <cstdio>

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

std::optional<TextProblem> toml_text_problem(std::string_view text, std::string* ascii) {
  if (auto bad = text_problem(text)) return bad;
  if (ascii) {
    ascii->clear();
    ascii->reserve(text.size() + text.size() / 8);
  }
  const auto emit = [&](std::string_view s) {
    if (ascii) ascii->append(s);
  };
  // A code point as a TOML escape (inside a string) or '?' (in a comment): toml++ sees ASCII.
  const auto emit_code_point = [&](std::size_t i, bool in_string) -> std::size_t {
    const auto b0 = static_cast<unsigned char>(text[i]);
    const std::size_t n = b0 >= 0xF0 ? 4 : b0 >= 0xE0 ? 3 : 2;
    if (!ascii) return n;
    if (!in_string) {
      ascii->push_back('?');
      return n;
    }
    uint32_t cp = b0 & (n == 2 ? 0x1F : n == 3 ? 0x0F : 0x07);
    for (std::size_t k = 1; k < n; ++k)
      cp = (cp << 6) | (static_cast<unsigned char>(text[i + k]) & 0x3F);
    char buf[16];
    std::snprintf(buf, sizeof buf, cp > 0xFFFF ? "\\U%08X" : "\\u%04X", static_cast<unsigned>(cp));
    ascii->append(buf);
    return n;
  };
  // The text is valid UTF-8 here: columns count code points.
  enum class Ctx { bare, comment, basic, literal, ml_basic, ml_literal };
  Ctx ctx = Ctx::bare;
  std::size_t line = 1, col = 1;
  // The last non-blank character outside strings and comments on this line ('\n' at its start):
  // a quote opens a string only where TOML lets one start (a key at the line's start or after
  // '.', a value after '=', '[', ',' or '{'); elsewhere (e.g. `0"x"`) toml++ reads it as part
  // of a bare value. Where this scan and toml++ still disagree, toml++ gets ASCII only (the
  // escapes below) and reports a parse error: never a non-ASCII character in its bare context.
  char prev = '\n';
  const auto string_may_start = [&] {
    return prev == '\n' || prev == '=' || prev == '[' || prev == ',' || prev == '{' || prev == '.';
  };
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
      if (ctx == Ctx::literal) emit("\"");  // literal strings are passed on as basic ones
      if (ctx == Ctx::comment || ctx == Ctx::basic || ctx == Ctx::literal) ctx = Ctx::bare;
      emit("\n");
      ++line;
      col = 1;
      ++i;
      if (ctx == Ctx::bare) prev = '\n';
      continue;
    }
    if (b >= 0x80) {
      if (ctx == Ctx::bare)
        return TextProblem{line, col, "non-ASCII character outside a string or comment"};
      i += emit_code_point(i, ctx != Ctx::comment);
      ++col;
      continue;
    }
    std::size_t len = 1;
    switch (ctx) {
      case Ctx::bare:
        if (b == '#') {
          ctx = Ctx::comment;
          emit("#");
        } else if ((b == '"' || b == '\'') && !string_may_start()) {
          prev = static_cast<char>(b);  // not a string here: what follows stays bare
          emit(text.substr(i, 1));
        } else if (starts(i, "\"\"\"")) {
          ctx = Ctx::ml_basic;
          len = 3;
          emit("\"\"\"");
        } else if (starts(i, "'''")) {
          ctx = Ctx::ml_literal;
          len = 3;
          emit("\"\"\"");
        } else if (b == '"') {
          ctx = Ctx::basic;
          emit("\"");
        } else if (b == '\'') {
          ctx = Ctx::literal;
          emit("\"");
        } else {
          if (b != ' ' && b != '\t' && b != '\r') prev = static_cast<char>(b);
          emit(text.substr(i, 1));
        }
        break;
      case Ctx::comment:
        emit(text.substr(i, 1));
        break;
      case Ctx::basic:
        if (b == '\\' && i + 1 < text.size() && text[i + 1] != '\n' &&
            static_cast<unsigned char>(text[i + 1]) < 0x80) {
          len = 2;  // an escaped character
        } else if (b == '"') {
          ctx = Ctx::bare;
          prev = '"';
        }
        emit(text.substr(i, len));
        break;
      case Ctx::literal:
        if (b == '\'') {
          ctx = Ctx::bare;
          prev = '\'';
          emit("\"");
        } else if (b == '\\' || b == '"') {
          emit(b == '\\' ? "\\\\" : "\\\"");
        } else {
          emit(text.substr(i, 1));
        }
        break;
      case Ctx::ml_basic:
      case Ctx::ml_literal: {
        const bool basic = ctx == Ctx::ml_basic;
        const char q = basic ? '"' : '\'';
        if (basic && b == '\\' && i + 1 < text.size() && text[i + 1] != '\n' &&
            static_cast<unsigned char>(text[i + 1]) < 0x80) {
          len = 2;
          emit(text.substr(i, 2));
        } else if (b == static_cast<unsigned char>(q)) {
          // The closing delimiter is the last three quotes of a run of three to five.
          const std::size_t n = run_of(i, q);
          if (n >= 3) {
            len = n < 5 ? n : 5;
            ctx = Ctx::bare;
            prev = q;
            emit(text.substr(i, len - 3));  // quotes of the content before the delimiter
            emit("\"\"\"");
          } else {
            len = n;
            emit(text.substr(i, len));
          }
        } else if (!basic && (b == '\\' || b == '"')) {
          emit(b == '\\' ? "\\\\" : "\\\"");
        } else {
          emit(text.substr(i, 1));
        }
        break;
      }
    }
    i += len;
    col += len;
  }
  if (ctx == Ctx::literal) emit("\"");
  return std::nullopt;
}

}  // namespace mocap
