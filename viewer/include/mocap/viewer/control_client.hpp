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

std::string status_request();

struct ControlReply {
  bool ok = false;
  std::string message;  ///< the daemon's message or error, or why it could not be reached
  std::string json;     ///< the reply line itself ("" if none came)
};

/// What the HUD prompts after a calibration, from a `status` reply: the calibration's refusal
/// reason while uncalibrated after a capture; "" when there is nothing to say. Upper case (the
/// HUD's font). Never throws.
std::string calibration_prompt(const std::string& status_reply_json);
/// Asks the daemon for its status (timeout_ms at most) and returns calibration_prompt() of it;
/// "" when no daemon answers.
std::string fetch_calibration_prompt(const std::string& socket_path, int timeout_ms = 100);

/// Connects, sends `request` plus '\n', waits up to `timeout_ms` for one reply line. A reply is
/// ok if it is a JSON object with "ok": true. Never throws.
ControlReply send_control_request(const std::string& socket_path, const std::string& request,
                                  int timeout_ms = 500);

}  // namespace mocap::viewer
