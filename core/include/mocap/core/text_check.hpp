// Checks text before it reaches a parser that assumes well-formed input (toml++ 3.3 has
// undefined behaviour on some malformed UTF-8): rejects NUL bytes and invalid UTF-8, naming
// the line and column of the first bad byte. Also the small text helpers the line parsers share.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace mocap {

struct TextProblem {
  std::size_t line = 0, column = 0;  ///< 1-based position of the first bad byte
  std::string what;                  ///< e.g. "invalid UTF-8 continuation byte"
  /// "line L, column C: what"
  std::string to_string() const {
    return "line " + std::to_string(line) + ", column " + std::to_string(column) + ": " + what;
  }
};

/// The first NUL byte or invalid UTF-8 sequence (overlong, surrogate, beyond U+10FFFF,
/// truncated), or nullopt if the text is clean. With ascii_only, any non-ASCII character is a
/// problem too.
std::optional<TextProblem> text_problem(std::string_view text, bool ascii_only = false);

/// What every TOML text goes through before toml++: text_problem (NUL, invalid UTF-8), then a
/// lexical scan that allows non-ASCII characters only inside comments and strings (basic,
/// literal, multi-line; quoted keys are strings). Outside them TOML 1.0 allows only ASCII, and
/// there toml++ 3.3 reaches __builtin_unreachable on some valid code points (U+03CF after a
/// bare value, found by fuzzing: tests/fuzz/corpus/config/regression-toml-non-ascii-after-value),
/// so such a character is reported at its position and never reaches toml++.
std::optional<TextProblem> toml_text_problem(std::string_view text);

/// `s` without leading and trailing spaces and tabs.
constexpr std::string_view trim_blanks(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t'))
    s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t'))
    s.remove_suffix(1);
  return s;
}

}  // namespace mocap
