// Blender (Debian's, headless) as a real third-party program in tests: whether it is installed,
// the command line that runs one of our Python scripts in it (`blender -b --factory-startup
// --python-exit-code 1 --python SCRIPT -- ARGS`: an exception in the script fails the run), and
// running it to completion with its output in a log file. Used by the BVH/glTF import tests
// (tests/skeleton) and the live-link add-on test (tests/blender).
#pragma once

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <string>
#include <vector>

extern char** environ;

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

/// Runs the script to completion (stdout and stderr into `log`); its exit status (128 + signal
/// when killed, -1 when Blender could not be started).
inline int run_blender(const std::string& script, const std::vector<std::string>& args,
                       const std::string& log) {
  std::vector<std::string> argv = blender_argv(script, args);
  std::vector<char*> a;
  for (auto& s : argv)
    a.push_back(s.data());
  a.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  pid_t pid = -1;
  const int spawned = posix_spawn(&pid, a[0], &fa, nullptr, a.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (spawned != 0) return -1;
  int st = 0;
  if (waitpid(pid, &st, 0) != pid) return -1;
  return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
}

}  // namespace mocap::test
