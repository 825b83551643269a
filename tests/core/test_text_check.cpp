// text_problem: NUL bytes and each kind of invalid UTF-8 are found at the right line and column;
// valid multi-byte text passes.
#include <gtest/gtest.h>

#include "mocap/core/text_check.hpp"

namespace mocap {

TEST(TextCheck, ValidTextPasses) {
  EXPECT_FALSE(text_problem("a = 1\nname = \"Jos\xC3\xA9 \xE2\x82\xAC \xF0\x9F\x98\x80\"\n"));
  EXPECT_FALSE(text_problem(""));
}

TEST(TextCheck, FindsTheFirstBadByteWithItsPosition) {
  using namespace std::string_literals;
  struct Case {
    std::string text;
    std::size_t line, column;
    const char* what;
  };
  const Case cases[] = {
      {"ab\ncd\0e"s, 2, 3, "NUL byte"},
      {"x = \xFF\n", 1, 5, "invalid UTF-8 lead byte"},
      {"\n\nk = \"\xC3(\"", 3, 6, "invalid UTF-8 continuation byte"},
      {"\xC0\xAF", 1, 1, "overlong UTF-8 sequence"},
      {"a\xED\xA0\x80", 1, 2, "UTF-8 encoded surrogate"},
      {"\xF4\x90\x80\x80", 1, 1, "UTF-8 code point beyond U+10FFFF"},
      {"ok\xE2\x82", 1, 3, "truncated UTF-8 sequence"},
  };
  for (const auto& c : cases) {
    const auto p = text_problem(c.text);
    ASSERT_TRUE(p.has_value()) << c.what;
    EXPECT_EQ(p->line, c.line) << c.what;
    EXPECT_EQ(p->column, c.column) << c.what;
    EXPECT_EQ(p->what, c.what);
  }
  EXPECT_EQ(text_problem("\n\xFF")->to_string(), "line 2, column 1: invalid UTF-8 lead byte");
}

TEST(TextCheck, AsciiOnlyRejectsValidNonAscii) {
  // U+03CF after a value sends toml++ 3.3 into __builtin_unreachable (fuzz finding).
  const std::string text = "a = 1\nb = 2\xCF\x8F\n";
  EXPECT_FALSE(text_problem(text));
  const auto p = text_problem(text, /*ascii_only=*/true);
  ASSERT_TRUE(p.has_value());
  EXPECT_EQ(p->line, 2u);
  EXPECT_EQ(p->column, 6u);
}

}  // namespace mocap
