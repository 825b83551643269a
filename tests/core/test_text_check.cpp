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

namespace mocap {

TEST(TomlTextCheck, NonAsciiInStringsAndCommentsPasses) {
  EXPECT_FALSE(
      toml_text_problem("# capteur du bassin \xE2\x80\x94 Jos\xC3\xA9\n"
                        "name = \"Jos\xC3\xA9\" # \xC3\xA9t\xC3\xA9\n"
                        "\"cl\xC3\xA9\" = 'capteur du bassin \xE2\x82\xAC'\n"
                        "a = \"\"\"x \xCF\x8F \\\" \"\"\"\"\" # \xCF\x8F\n"
                        "b = '''y\n\xCF\x8F'''\n"
                        "c = \"esc \\\\\" # \xCF\x8F after an escaped backslash\n"));
}

TEST(TomlTextCheck, NonAsciiOutsideStringsIsRefusedAtItsPosition) {
  struct Case {
    std::string text;
    std::size_t line, column;
  };
  const Case cases[] = {
      {"a = 1\nb = 2\xCF\x8F\n", 2, 6},            // the toml++ 3.3 fuzz finding
      {"n = \"Jos\xC3\xA9\" \xC3\xA9\n", 1, 12},   // after a closed string (column in code points)
      {"Jos\xC3\xA9 = 1\n", 1, 4},                 // bare key
      {"s = \"open\nx = \xC3\xA9\n", 2, 5},        // a single-line string ends at the newline
      {"m = \"\"\"a\"\"\"\"\"\xC3\xA9\n", 1, 14},  // five closing quotes end the string
      {"#set semo zhz=2is_rema\xCF\x8F\xC2\x81z=2\n", 0, 0},  // in a comment: fine
      // A quote where no string may start is part of a bare value for toml++ (libFuzzer
      // finding: `name =0"Jos\xC3\xA9"` reached toml++'s undefined whitespace test).
      {"name =0\"Jos\xC3\xA9\"\n", 1, 12},
      {"x = \"a\" \"\xC3\xA9\"\n", 1, 10},
      {"[t]\nk = [\"a\", \"\xC3\xA9\"]\nv = {a = \"\xC3\xA9\"}\n[u.\"\xC3\xA9\"]\n", 0, 0},
  };
  for (const auto& c : cases) {
    const auto p = toml_text_problem(c.text);
    if (c.line == 0) {
      EXPECT_FALSE(p) << c.text;
      continue;
    }
    ASSERT_TRUE(p.has_value()) << c.text;
    EXPECT_EQ(p->line, c.line) << c.text;
    EXPECT_EQ(p->column, c.column) << c.text;
    EXPECT_EQ(p->what, "non-ASCII character outside a string or comment");
  }
  // Invalid UTF-8 is still refused first, even inside a string.
  const auto bad = toml_text_problem("n = \"Jos\xC3(\"\n");
  ASSERT_TRUE(bad);
  EXPECT_EQ(bad->what, "invalid UTF-8 continuation byte");
  EXPECT_EQ(bad->column, 9u);
}

}  // namespace mocap

namespace mocap {
namespace {

// What toml++ reads: the same document in ASCII (strings' non-ASCII as escapes, literal strings
// as basic ones, comments' as '?'), so no non-ASCII byte reaches toml++ even where the scan and
// toml++ disagree on what a string is (libFuzzer: `v = 2x='''...`).
TEST(TomlTextCheck, TomlPlusPlusReadsAsciiOnly) {
  std::string out;
  ASSERT_FALSE(
      toml_text_problem("a = 'x\\\"\xC3\xA9' # \xC3\xA9\nb = \"\xF0\x9F\x98\x80\"\n"
                        "c = '''\xC3\xA9'''\n",
                        &out));
  EXPECT_EQ(out, "a = \"x\\\\\\\"\\u00E9\" # ?\nb = \"\\U0001F600\"\nc = \"\"\"\\u00E9\"\"\"\n");
  const std::string fuzzed = "v = 2is_reme~z='''2=hz00s\xC3\xA9 t=/dev/pts/1\n";
  if (!toml_text_problem(fuzzed, &out)) {
    for (char ch : out)
      EXPECT_LT(static_cast<unsigned char>(ch), 0x80) << out;
  }
}

}  // namespace
}  // namespace mocap
