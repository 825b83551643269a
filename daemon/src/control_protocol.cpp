// The control request grammar: one line of words, parsed strictly (printable ASCII/UTF-8 only,
// bounded length, exact command words and argument counts).
#include <nlohmann/json.hpp>

#include "mocap/core/text_check.hpp"
#include "mocap/daemon/control.hpp"

namespace mocap::daemon {

namespace {

std::string_view next_word(std::string_view& s) {
  s = trim_blanks(s);
  size_t n = 0;
  while (n < s.size() && s[n] != ' ' && s[n] != '\t')
    ++n;
  std::string_view w = s.substr(0, n);
  s.remove_prefix(n);
  s = trim_blanks(s);
  return w;
}

}  // namespace

std::optional<ControlRequest> parse_control_request(std::string_view line, std::string& error) {
  if (line.size() > kMaxControlRequest) {
    error = "request too long (max " + std::to_string(kMaxControlRequest) + " bytes)";
    return std::nullopt;
  }
  if (!line.empty() && line.back() == '\n') line.remove_suffix(1);
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  for (char ch : line) {
    const auto c = static_cast<unsigned char>(ch);
    if (c < 0x20 && c != '\t') {
      error = "request contains control characters";
      return std::nullopt;
    }
    if (c == 0x7f) {
      error = "request contains control characters";
      return std::nullopt;
    }
  }
  std::string_view rest = line;
  const std::string_view cmd = next_word(rest);
  ControlRequest r;
  auto no_args = [&](ControlCommand c) -> std::optional<ControlRequest> {
    if (!rest.empty()) {
      error = "'" + std::string(cmd) + "' takes no argument";
      return std::nullopt;
    }
    r.command = c;
    return r;
  };
  if (cmd.empty()) {
    error = "empty request";
    return std::nullopt;
  }
  if (cmd == "status") return no_args(ControlCommand::status);
  if (cmd == "reset-heading") return no_args(ControlCommand::reset_heading);
  if (cmd == "quit") return no_args(ControlCommand::quit);
  if (cmd == "calibrate") {
    // none: the configured calibration.pose; mounting: an N-pose, then the mounting motion
    const std::string_view pose = next_word(rest);
    if ((!pose.empty() && pose != "npose" && pose != "tpose" && pose != "mounting") ||
        !rest.empty()) {
      error = "usage: calibrate [npose|tpose|mounting]";
      return std::nullopt;
    }
    r.command = ControlCommand::calibrate;
    r.argument = std::string(pose);
    return r;
  }
  if (cmd == "record") {
    const std::string_view what = next_word(rest);
    if (what == "stop") return no_args(ControlCommand::record_stop);
    if (what == "start") {
      r.command = ControlCommand::record_start;
      r.argument = std::string(rest);  // the rest of the line: file names may contain spaces;
                                       // none: the daemon picks a fresh take name
      return r;
    }
    error = "usage: record start [NAME] | record stop";
    return std::nullopt;
  }
  error = "unknown command '" + std::string(cmd.substr(0, 64)) +
          "' (commands: status, calibrate, reset-heading, record, quit)";
  return std::nullopt;
}

std::string format_control_request(const ControlRequest& r) {
  switch (r.command) {
    case ControlCommand::status:
      return "status\n";
    case ControlCommand::calibrate:
      return r.argument.empty() ? "calibrate\n" : "calibrate " + r.argument + "\n";
    case ControlCommand::reset_heading:
      return "reset-heading\n";
    case ControlCommand::record_start:
      return r.argument.empty() ? "record start\n" : "record start " + r.argument + "\n";
    case ControlCommand::record_stop:
      return "record stop\n";
    case ControlCommand::quit:
      return "quit\n";
  }
  return "\n";
}

std::string control_error_reply(std::string_view message) {
  nlohmann::json j{{"ok", false}, {"error", std::string(message)}};
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace mocap::daemon
