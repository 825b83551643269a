// Hostile or careless configuration files against the real mocapd --check-config (issue 20,
// item 5): a directory is an error, a file over 1 MiB is refused without being read whole,
// thousands of problems stop after 50 with a clear message, long values are cut in messages.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <string>

#include "harness.hpp"

using namespace mocap::reliability;

namespace {

struct CheckRun {
  int code = -1;
  std::string out;
};

CheckRun check_config(const std::string& path) {
  const Result r = run_bin("mocapd", {"--check-config", path}, 60);
  return {r.code, r.err + r.out};
}

}  // namespace

TEST(ConfigLimits, ADirectoryIsNotAConfiguration) {
  TempDir dir;
  const CheckRun r = check_config(dir.path());
  EXPECT_NE(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("is a directory"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("OK"), std::string::npos) << r.out;
}

TEST(ConfigLimits, AHugeFileIsRefusedWithoutReadingItAll) {
  TempDir dir;
  const std::string path = dir.file("huge.toml");
  {
    std::ofstream f(path, std::ios::binary);
    const std::string line = "key_" + std::string(40, 'k') + " = 1\n";
    for (size_t written = 0; written < (40u << 20); written += line.size())
      f << line;  // 40 MiB of unknown keys
  }
  const CheckRun r = check_config(path);
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.out.find("1 MiB"), std::string::npos) << r.out.substr(0, 2000);
  EXPECT_LT(r.out.size(), 2000u) << r.out.substr(0, 2000);
}

TEST(ConfigLimits, ManyProblemsStopAfterFiftyAndLongValuesAreCut) {
  TempDir dir;
  const std::string many = dir.file("many.toml");
  {
    std::ofstream f(many);
    for (int i = 0; i < 20000; ++i)
      f << "unknown_" << i << " = " << i << "\n";  // ~400 KB: under the size limit
  }
  CheckRun r = check_config(many);
  EXPECT_NE(r.code, 0);
  const auto lines = std::count(r.out.begin(), r.out.end(), '\n');
  EXPECT_LE(lines, 53) << r.out.substr(0, 3000);
  EXPECT_NE(r.out.find("more than 50 problems: stopped checking"), std::string::npos)
      << r.out.substr(0, 3000);

  const std::string longv = dir.file("long.toml");
  {
    std::ofstream f(longv);
    f << "[daemon]\nlog_level = \"" << std::string(500000, 'x') << "\"\n"
      << std::string(100000, 'y') << " = 1\n";
  }
  r = check_config(longv);
  EXPECT_NE(r.code, 0);
  EXPECT_LT(r.out.size(), 4000u) << r.out.substr(0, 4000);
  EXPECT_NE(r.out.find("more bytes not shown"), std::string::npos) << r.out.substr(0, 4000);
}
