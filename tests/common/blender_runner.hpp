// Blender (Debian's, headless) as a real third-party program in tests: whether it is installed,
// the command line that runs one of our Python scripts in it (`blender -b --factory-startup
// --python-exit-code 1 --python SCRIPT -- ARGS`: an exception in the script fails the run), and
// running it to completion with its output in a log file. Used by the BVH/glTF import tests
// (tests/skeleton) and the live-link add-on test (tests/blender).
#pragma once

#include <unistd.h>

#include <fstream>
#include <string>
#include <vector>

#include "run_program.hpp"

namespace mocap::test {

inline constexpr const char* kBlenderPath = "/usr/bin/blender";

inline bool have_blender() {
  return ::access(kBlenderPath, X_OK) == 0;
}

/// The argv that runs `script` headless in a factory-fresh Blender with `args` after "--"
/// (the script reads them after sys.argv.index("--")).
inline std::vector<std::string> blender_argv(const std::string& script,
                                             const std::vector<std::string>& args) {
  std::vector<std::string> a = {
      kBlenderPath, "-b", "--factory-startup", "--python-exit-code", "1", "--python", script, "--"};
  a.insert(a.end(), args.begin(), args.end());
  return a;
}

/// Runs the script to completion (its stdout, then its stderr, into `log`); its exit status
/// (128 + signal when killed, -1 when Blender could not be started).
inline int run_blender(const std::string& script, const std::vector<std::string>& args,
                       const std::string& log) {
  const Result r = run(blender_argv(script, args));
  std::ofstream(log, std::ios::binary) << r.out << r.err;
  return r.code;
}

}  // namespace mocap::test
