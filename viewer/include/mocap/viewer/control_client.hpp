// The viewer's only link to the daemon's control socket: one text request line ("calibrate
// npose", "reset-heading"), one JSON reply line ({"ok":true,...} / {"ok":false,"error":...}),
// over the Unix socket at $XDG_RUNTIME_DIR/mocapd.sock (mocap/daemon/control.hpp defines the
// protocol). Isolated here so the viewer links only core and skeleton, not the daemon.
#pragma once

#include <string>

namespace mocap::viewer {

/// $XDG_RUNTIME_DIR/mocapd.sock, or /tmp/mocapd-<uid>.sock without XDG_RUNTIME_DIR.
std::string default_control_socket_path();

/// Request lines (no trailing newline).
std::string calibrate_request(const std::string& pose);  ///< pose: "npose" or "tpose"
std::string heading_reset_request();

struct ControlReply {
  bool ok = false;
  std::string message;  ///< the daemon's message or error, or why it could not be reached
};

/// Connects, sends `request` plus '\n', waits up to `timeout_ms` for one reply line. A reply is
/// ok if it is a JSON object with "ok": true. Never throws.
ControlReply send_control_request(const std::string& socket_path, const std::string& request,
                                  int timeout_ms = 500);

}  // namespace mocap::viewer
