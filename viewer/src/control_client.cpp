// Control-socket client: Unix stream socket, one JSON line each way, bounded wait.
#include "mocap/viewer/control_client.hpp"

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <nlohmann/json.hpp>

#include "mocap/core/runtime_dir.hpp"
#include "mocap/core/time.hpp"

namespace mocap::viewer {

std::string default_control_socket_path() {
  // The daemon's private runtime directory (mocap/core/runtime_dir.hpp); if there is none the
  // path names the reason's directory and connecting fails with a message.
  std::string error;
  const std::string dir = private_runtime_dir(&error);
  return (dir.empty() ? "/nonexistent-private-runtime-dir" : dir) + "/mocapd.sock";
}

// Request lines of the daemon's control protocol (mocap/daemon/control.hpp).
std::string calibrate_request(const std::string& pose) {
  return "calibrate " + pose;
}

std::string status_request() {
  return "status";
}

std::string calibration_prompt(const std::string& status_reply_json) {
  const auto j = nlohmann::json::parse(status_reply_json, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("calibration")) return "";
  const auto& c = j["calibration"];
  if (!c.is_object()) return "";
  const auto upper = [](std::string s) {
    for (char& ch : s)
      ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
    return s;
  };
  const std::string message = c.value("message", std::string());
  if (!j.value("calibrated", false)) return message.empty() ? "" : "CALIBRATION: " + upper(message);
  return "";
}

std::string fetch_calibration_prompt(const std::string& socket_path, int timeout_ms) {
  const ControlReply r = send_control_request(socket_path, status_request(), timeout_ms);
  return r.ok ? calibration_prompt(r.json) : std::string();
}

std::string heading_reset_request() {
  return "reset-heading";
}

namespace {

struct Fd {
  int fd;
  ~Fd() {
    if (fd >= 0) close(fd);
  }
};

ControlReply fail(const std::string& what, const std::string& path) {
  return {false, what + " " + path + ": " + std::strerror(errno)};
}

}  // namespace

ControlReply send_control_request(const std::string& path, const std::string& request,
                                  int timeout_ms) {
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  if (path.size() >= sizeof addr.sun_path) return {false, "socket path too long: " + path};
  std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
  Fd s{socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0)};
  if (s.fd < 0) return fail("socket", path);
  if (connect(s.fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0)
    return fail("daemon not reachable at", path);
  const std::string line = request + "\n";
  for (size_t sent = 0; sent < line.size();) {
    const ssize_t n = send(s.fd, line.data() + sent, line.size() - sent, MSG_NOSIGNAL);
    if (n <= 0) return fail("send to", path);
    sent += static_cast<size_t>(n);
  }
  std::string reply;
  const int64_t deadline_ns = monotonic_ns() + static_cast<int64_t>(timeout_ms) * 1000000;
  char buf[512];
  while (reply.find('\n') == std::string::npos) {
    const int64_t left_ms = (deadline_ns - monotonic_ns()) / 1000000;
    if (left_ms <= 0)
      return {false, "no reply from daemon within " + std::to_string(timeout_ms) + " ms"};
    pollfd p{s.fd, POLLIN, 0};
    if (poll(&p, 1, static_cast<int>(left_ms)) <= 0) continue;
    const ssize_t n = recv(s.fd, buf, sizeof buf, 0);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    reply.append(buf, static_cast<size_t>(n));
    if (reply.size() > 65536) return {false, "daemon reply too long"};
  }
  if (const auto nl = reply.find('\n'); nl != std::string::npos) reply.resize(nl);
  if (reply.empty()) return {false, "daemon closed the connection without a reply"};
  const auto j = nlohmann::json::parse(reply, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return {false, "daemon reply is not JSON: " + reply};
  ControlReply r;
  r.json = reply;
  r.ok = j.value("ok", false);
  if (j.contains("error") && j["error"].is_string())
    r.message = j["error"].get<std::string>();
  else if (j.contains("message") && j["message"].is_string())
    r.message = j["message"].get<std::string>();
  else
    r.message = r.ok ? "ok" : reply;
  return r;
}

}  // namespace mocap::viewer
