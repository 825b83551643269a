// CliArgs: options, flags, positionals and the errors users see.
#include <gtest/gtest.h>

#include "mocap/core/cli_args.hpp"

namespace mocap {
namespace {

bool parse(CliArgs& a, std::vector<std::string> v) {
  std::vector<char*> argv{const_cast<char*>("prog")};
  for (auto& s : v)
    argv.push_back(s.data());
  return a.parse(static_cast<int>(argv.size()), argv.data());
}

}  // namespace

TEST(CliArgs, ParsesOptionsFlagsAndPositionals) {
  CliArgs a;
  a.option("mode", "").flag("verbose", "").multi("set", "");
  std::vector<std::string> v{"in.csv",    "--mode", "6d",  "--verbose",
                             "--set=a=1", "--set",  "b=2", "out.csv"};
  ASSERT_TRUE(parse(a, v)) << a.error();
  EXPECT_EQ(a.get("mode").value(), "6d");
  EXPECT_TRUE(a.has("verbose"));
  EXPECT_EQ(a.get_all("set"), (std::vector<std::string>{"a=1", "b=2"}));
  EXPECT_EQ(a.positional(), (std::vector<std::string>{"in.csv", "out.csv"}));
}

TEST(CliArgs, RejectsUnknownMissingAndMalformed) {
  {
    CliArgs a;
    a.option("rate", "");
    EXPECT_FALSE(parse(a, {"--bogus"}));
    EXPECT_EQ(a.error(), "unknown option --bogus");
  }
  {
    CliArgs a;
    a.option("rate", "");
    EXPECT_FALSE(parse(a, {"--rate"}));
    EXPECT_EQ(a.error(), "option --rate needs a value");
  }
  {
    CliArgs a;
    a.option("rate", "");
    ASSERT_TRUE(parse(a, {"--rate", "12x"}));
    double r = 0;
    EXPECT_FALSE(a.get_double("rate", r));
    EXPECT_EQ(a.error(), "option --rate: '12x' is not a number");
  }
}

}  // namespace mocap
