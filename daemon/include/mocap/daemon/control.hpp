// The control socket: mocapctl's requests to a running mocapd. One request per connection, a
// single text line ("status", "calibrate npose", "record start FILE", ...); the reply is one
// line of JSON ({"ok":true,...} or {"ok":false,"error":"..."}). The socket is a Unix-domain
// stream socket with mode 0600; malformed or oversized requests get an error reply.
#pragma once

#include <atomic>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <thread>

#include "mocap/core/log.hpp"
#include "mocap/core/wakeup.hpp"

namespace mocap::daemon {

inline constexpr size_t kMaxControlRequest = 4096;

enum class ControlCommand { status, calibrate, reset_heading, record_start, record_stop, quit };

struct ControlRequest {
  ControlCommand command = ControlCommand::status;
  std::string argument;  ///< "npose"/"tpose" for calibrate, the file for record start ("" = fresh)
  bool unique = false;   ///< record start (not on the wire): a -N suffix if the name is taken
};

/// Parses one request line (without or with its trailing newline). Returns the request, or
/// nullopt and an error message naming the problem.
std::optional<ControlRequest> parse_control_request(std::string_view line, std::string& error);
/// The request as a line (inverse of parse_control_request), newline included.
std::string format_control_request(const ControlRequest& r);
/// {"ok":false,"error":"..."} with proper JSON escaping.
std::string control_error_reply(std::string_view message);

/// Serves the socket on its own thread; the handler runs on that thread and returns the reply.
class ControlServer {
 public:
  using Handler = std::function<std::string(const ControlRequest&)>;
  /// Binds the socket (replacing a stale one; refusing if a live daemon answers there).
  /// Throws std::runtime_error naming the path on failure.
  ControlServer(std::string path, Handler handler, Logger log);
  ~ControlServer();
  ControlServer(const ControlServer&) = delete;
  ControlServer& operator=(const ControlServer&) = delete;

  const std::string& path() const { return path_; }
  uint64_t requests_served() const { return served_.load(); }

 private:
  void run();
  void serve_one(int fd);

  std::string path_;
  Handler handler_;
  Logger log_;
  int listen_fd_ = -1;
  Wakeup stop_;
  std::atomic<bool> stopping_{false};
  std::atomic<uint64_t> served_{0};
  std::thread thread_;
};

/// Client side (mocapctl, tests): sends one request, returns the reply line (without newline).
/// Throws std::runtime_error when the daemon cannot be reached.
std::string control_call(const std::string& path, std::string_view request_line,
                         int timeout_ms = 5000);

}  // namespace mocap::daemon
