// Helpers for end-to-end tests that run the real programs: spawn with output to files, bounded
// waits, whole-file reads (run_program.hpp's slurp_file), and a JSON pose-stream reader.
#pragma once

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "run_program.hpp"

extern char** environ;

namespace mocap::test {

inline const std::string kBinDir = std::string(MOCAP_BINARY_DIR) + "/bin/";

/// Starts argv[0] with stdout to out_file and stderr to out_file + ".err" (if given); -1 on
/// failure.
inline pid_t spawn(const std::vector<std::string>& argv, const std::string& out_file = "") {
  std::vector<char*> a;
  for (const auto& s : argv)
    a.push_back(const_cast<char*>(s.c_str()));
  a.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  if (!out_file.empty()) {
    posix_spawn_file_actions_addopen(&fa, 1, out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&fa, 2, (out_file + ".err").c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
  }
  pid_t pid = -1;
  if (posix_spawn(&pid, a[0], &fa, nullptr, a.data(), environ) != 0) pid = -1;
  posix_spawn_file_actions_destroy(&fa);
  return pid;
}

/// The exit status (128 + signal if killed); kills it and returns -1 after timeout_s.
inline int wait_exit(pid_t pid, int timeout_s = 30) {
  for (int i = 0; i < timeout_s * 100; ++i) {
    int st = 0;
    if (waitpid(pid, &st, WNOHANG) == pid)
      return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  kill(pid, SIGKILL);
  waitpid(pid, nullptr, 0);
  return -1;
}

/// Runs argv to completion (120 s at most), its stdout into *out.
inline int run_program(const std::vector<std::string>& argv, const std::string& out_file,
                       std::string* out = nullptr) {
  const int rc = wait_exit(spawn(argv, out_file), 120);
  if (out) *out = slurp_file(out_file) + slurp_file(out_file + ".err");
  return rc;
}

/// Reads up to `count` JSON lines from the pose stream at 127.0.0.1:port (10 s at most).
/// Connects to a JSON-lines output and reads `count` lines (10 s at most); on_first, if given,
/// is called once the first line has arrived (a test can start a motion at a known frame).
inline std::vector<nlohmann::json> read_json_lines(uint16_t port, int count,
                                                   const std::function<void()>& on_first = {}) {
  std::vector<nlohmann::json> out;
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    close(fd);
    return out;
  }
  std::string buf;
  char chunk[8192];
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (static_cast<int>(out.size()) < count && std::chrono::steady_clock::now() < deadline) {
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, 500) <= 0) continue;
    const ssize_t n = recv(fd, chunk, sizeof chunk, 0);
    if (n <= 0) break;
    buf.append(chunk, static_cast<size_t>(n));
    size_t nl;
    while ((nl = buf.find('\n')) != std::string::npos && static_cast<int>(out.size()) < count) {
      out.push_back(nlohmann::json::parse(buf.substr(0, nl)));
      buf.erase(0, nl + 1);
      if (out.size() == 1 && on_first) on_first();
    }
  }
  close(fd);
  return out;
}

}  // namespace mocap::test
