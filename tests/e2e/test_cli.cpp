// The command lines of the four programs (issue 22 item 8): -h/--help and --version of every
// program and every subcommand (found by reading the programs' own help, so a new subcommand is
// covered without touching this file) exit 0 with output; conflicting options exit 2 and name
// both options; a usage error names the program and the problem.
#include <gtest/gtest.h>

#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "../common/run_program.hpp"

namespace {

using mocap::test::Result;
using mocap::test::run;

const std::string kBin = std::string(MOCAP_BINARY_DIR) + "/bin/";

/// The subcommand names listed in a help text's "Subcommands:" section.
std::vector<std::string> subcommands_in(const std::string& help) {
  std::vector<std::string> names;
  std::istringstream in(help);
  std::string line;
  bool inside = false;
  while (std::getline(in, line)) {
    if (line == "Subcommands:") {
      inside = true;
      continue;
    }
    if (!inside) continue;
    if (line.empty() || line[0] != ' ') break;
    std::istringstream words(line);
    std::string name;
    words >> name;
    names.push_back(name);
  }
  return names;
}

/// Every command path of a program: {prog}, {prog, sub}, {prog, sub, subsub}, ...
void collect(std::vector<std::string> path, std::vector<std::vector<std::string>>& out) {
  out.push_back(path);
  path.push_back("--help");
  const Result r = run(path);
  path.pop_back();
  for (const std::string& s : subcommands_in(r.out)) {
    path.push_back(s);
    collect(path, out);
    path.pop_back();
  }
}

std::vector<std::string> programs() {
  std::vector<std::string> p = {kBin + "mocapd", kBin + "mocapctl", kBin + "mocap"};
#ifdef MOCAP_VIEWER_EXE
  p.push_back(MOCAP_VIEWER_EXE);
#endif
  return p;
}

/// The lines of a help text where a label that lists options ("Excludes:", "Needs:") lists
/// none (CLI11 writes a hidden option's name as "").
std::vector<std::string> empty_option_lists(const std::string& help) {
  std::vector<std::string> bad;
  std::istringstream in(help);
  for (std::string line; std::getline(in, line);)
    for (const std::string label : {"Excludes:", "Needs:"})
      for (std::size_t at = line.find(label); at != std::string::npos;
           at = line.find(label, at + 1)) {
        const std::size_t next = at + label.size();
        if (line.compare(next, 2, " -") != 0) bad.push_back(line);
      }
  return bad;
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& w : v)
    s += (s.empty() ? "" : " ") + w;
  return s;
}

}  // namespace

TEST(Cli, EveryProgramAndSubcommandHasHelpAndVersion) {
  std::vector<std::vector<std::string>> commands;
  for (const std::string& p : programs())
    collect({p}, commands);
  // mocapd, mocapctl (5 commands, record's 2), mocap (10 commands, bench's 6), the viewer.
  EXPECT_GE(commands.size(), 3u + 7u + 16u);
  bool saw_bench_latency = false;
  for (const auto& c : commands) {
    saw_bench_latency = saw_bench_latency || joined(c).ends_with("mocap bench latency");
    for (const char* flag : {"-h", "--help", "--version"}) {
      std::vector<std::string> argv = c;
      argv.push_back(flag);
      const Result r = run(argv);
      EXPECT_EQ(r.code, 0) << joined(argv) << "\n" << r.err;
      EXPECT_FALSE(r.out.empty()) << joined(argv);
      if (std::string(flag) == "--version")
        EXPECT_NE(r.out.find(MOCAP_PROJECT_VERSION), std::string::npos) << r.out;
      else {
        EXPECT_NE(r.out.find("Usage:"), std::string::npos) << joined(argv) << "\n" << r.out;
        for (const std::string& line : empty_option_lists(r.out))
          ADD_FAILURE() << joined(argv) << ": a label listing no option: " << line;
      }
    }
  }
  EXPECT_TRUE(saw_bench_latency);
}

TEST(Cli, HelpShowsDefaults) {
  const Result r = run({kBin + "mocap", "bench", "latency", "--help"});
  EXPECT_NE(r.out.find("=17"), std::string::npos) << r.out;  // --sensors 17
  const Result d = run({kBin + "mocapctl", "--help"});
  EXPECT_NE(d.out.find("=5000"), std::string::npos) << d.out;  // --timeout-ms
}

TEST(Cli, ConflictingOptionsSayWhich) {
  struct Case {
    std::vector<std::string> argv;
    std::string a, b;
  };
  std::vector<Case> cases = {
      {{kBin + "mocapd", "--check-config", "a.toml", "--config", "b.toml"},
       "--check-config",
       "--config"},
      {{kBin + "mocapd", "--demo", "--replay", "s.mocapses"}, "--demo", "--replay"},
      {{kBin + "mocap", "export", "s.mocapses", "--csv", "a.csv", "--bvh", "a.bvh"},
       "--csv",
       "--bvh"},
      {{kBin + "mocap", "simulate", "--protocol", "line", "--pty", "--udp", "127.0.0.1:9"},
       "--pty",
       "--udp"},
      {{kBin + "mocap", "replay", "s.mocapses", "--csv", "a.csv", "--poses", "b.csv"},
       "--csv",
       "--poses"},
  };
#ifdef MOCAP_VIEWER_EXE
  cases.push_back(
      {{MOCAP_VIEWER_EXE, "--connect", "h:1", "--play", "f.bvh"}, "--connect", "--play"});
  cases.push_back(
      {{MOCAP_VIEWER_EXE, "--bench", "--screenshot", "x.png"}, "--bench", "--screenshot"});
#endif
  for (const Case& c : cases) {
    const Result r = run(c.argv);
    EXPECT_EQ(r.code, 2) << joined(c.argv);
    EXPECT_NE(r.err.find(c.a), std::string::npos) << joined(c.argv) << "\n" << r.err;
    EXPECT_NE(r.err.find(c.b), std::string::npos) << joined(c.argv) << "\n" << r.err;
    EXPECT_NE(r.err.find("excludes"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("excludes \n"), std::string::npos) << r.err;  // names what it excludes
  }
  // Why: each conflicting option is shown with its description.
  const Result why = run(cases[0].argv);
  EXPECT_NE(why.err.find("--check-config: validate a configuration file and exit (runs nothing"),
            std::string::npos)
      << why.err;
  // A value that needs another option says which.
  const Result speed = run({kBin + "mocapd", "--speed", "2"});
  EXPECT_EQ(speed.code, 2);
  EXPECT_NE(speed.err.find("--speed requires --replay"), std::string::npos) << speed.err;
}

TEST(Cli, UsageErrorsNameTheCommandAndTheProblem) {
  const Result r = run({kBin + "mocap", "bench", "latency", "--sensors", "99"});
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.err.find("mocap bench latency:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--sensors"), std::string::npos) << r.err;
  const Result u = run({kBin + "mocapctl", "status", "--no-such-option"});
  EXPECT_EQ(u.code, 2);
  EXPECT_NE(u.err.find("--no-such-option"), std::string::npos) << u.err;
  const Result none = run({kBin + "mocap"});
  EXPECT_EQ(none.code, 2);
  EXPECT_NE(none.err.find("subcommand is required"), std::string::npos) << none.err;
}

TEST(Cli, DeprecatedSpellingsStillWorkAndWarn) {
  const std::string csv = "/tmp/mocap-cli-poses-" + std::to_string(getpid()) + ".csv";
  const Result r = run({kBin + "mocap", "replay",
                        std::string(MOCAP_SOURCE_DIR) + "/tests/data/demo_direct_50hz.mcap",
                        "--poses", csv, "--quiet"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("mocap replay: warning: --poses is deprecated; use --csv"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.out.find(csv), std::string::npos) << r.out;  // written where --poses said
  std::remove(csv.c_str());
}
