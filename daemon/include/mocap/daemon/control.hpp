// The control socket: mocapctl's requests to a running mocapd. One request per connection, a
// single text line ("status", "calibrate npose", "record start FILE", ...); the reply is one
// line of JSON ({"ok":true,...} or {"ok":false,"error":"..."}). The socket is a Unix-domain
// stream socket with mode 0600; malformed or oversized requests get an error reply.
// Connections are served independently by one thread with non-blocking sockets and
// per-connection buffers: a silent client delays nobody (it is closed after 2 s, or when 32
// are open and a new one arrives, oldest first); a request whose client has hung up before it
// is run is dropped, not run; when the fd limit is reached a reserve fd is given up to accept
// the connection, and accepting pauses for 100 ms if even that is gone (never a busy loop).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "mocap/core/log.hpp"
#include "mocap/core/wakeup.hpp"

namespace mocap::daemon {

inline constexpr size_t kMaxControlRequest = 4096;
inline constexpr size_t kMaxControlConnections = 32;

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
  /// Requests dropped unrun because their client had hung up.
  uint64_t requests_abandoned() const { return abandoned_.load(); }

 private:
  struct Conn {
    int fd = -1;
    std::string in, out;  ///< request bytes so far; reply bytes still to send
    std::size_t out_pos = 0;
    int64_t deadline_ns = 0;  ///< request complete or reply sent by then, else closed
    int64_t accepted_ns = 0;
    bool replying = false;
  };
  void run();
  void accept_connections(int64_t now);
  /// Reads what arrived; returns false when the connection is to be closed.
  bool on_input(Conn& c, short revents);
  /// Runs the request (unless its client hung up) and queues the reply.
  void answer(Conn& c, bool complete, bool too_long);
  /// Sends queued reply bytes; false when done or failed (close it).
  bool send_reply(Conn& c);
  void close_conn(std::size_t i);

  std::vector<Conn> conns_;
  int reserve_fd_ = -1;
  int64_t accept_paused_until_ = 0;
  std::atomic<uint64_t> abandoned_{0};

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
