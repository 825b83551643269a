// Control-socket client: the daemon's request lines, one JSON reply line each
// (mocap/core/unix_line_client.hpp does the socket), and the calibration prompt from a status.
#include "mocap/viewer/control_client.hpp"

#include <cctype>
#include <nlohmann/json.hpp>

#include "mocap/core/runtime_dir.hpp"
#include "mocap/core/unix_line_client.hpp"

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

ControlReply send_control_request(const std::string& path, const std::string& request,
                                  int timeout_ms) {
  std::string reply;
  try {
    reply = unix_line_call(path, request, timeout_ms, "mocapd");
  } catch (const std::exception& e) {
    return {false, e.what()};
  }
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
