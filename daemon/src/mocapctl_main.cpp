// mocapctl: control client for a running mocapd (talks over its Unix-domain control socket).
//   mocapctl status [--json] | calibrate npose|tpose | reset-heading | record start [NAME] |
//            record stop | quit          [--socket PATH]
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "mocap/core/cli_args.hpp"
#include "mocap/daemon/config.hpp"
#include "mocap/daemon/control.hpp"

namespace {

const char* kUsage =
    "usage: mocapctl COMMAND [options]\n"
    "commands:\n"
    "  status [--json]          sensors, rates, drops, filter and calibration state\n"
    "  calibrate npose|tpose    start a calibration (countdown, then hold the pose)\n"
    "  reset-heading            re-align the heading (stand upright facing forward)\n"
    "  record start [NAME]      record a session into a new file NAME inside the daemon's\n"
    "                           recording.directory (never overwritten: an existing file is an\n"
    "                           error); no NAME: a fresh take-YYYYMMDD-HHMMSS.mocapses\n"
    "  record stop              close the recording; prints duration, frames, samples, drops,\n"
    "                           bytes\n"
    "  quit                     stop the daemon\n"
    "options:\n";

void print_status_table(const nlohmann::json& j) {
  std::printf("mocapd: up %.0f s, frame %llu, %llu samples, %s%s%s\n", j.value("uptime_s", 0.0),
              static_cast<unsigned long long>(j.value("frame", 0ull)),
              static_cast<unsigned long long>(j.value("samples", 0ull)),
              j.value("calibrated", false) ? "calibrated" : "not calibrated",
              j.value("calibrating", false) ? " (calibrating)" : "",
              j.value("demo", false) ? ", demo" : "");
  if (const auto cal = j.find("calibration"); cal != j.end() && cal->is_object()) {
    const std::string msg = cal->value("message", std::string());
    if (!msg.empty()) std::printf("calibration: %s\n", msg.c_str());
  }
  const std::string rec = j.value("recording", std::string());
  std::printf("recording: %s\n", rec.empty() ? "no" : rec.c_str());
  std::printf("%-16s %-12s %-10s %8s %9s %7s %7s %5s %5s %9s %8s\n", "SENSOR", "SEGMENT", "STATE",
              "RATE_HZ", "AGE_MS", "DROPS", "ERRORS", "REST", "MAG", "BIAS_DPS", "HDG_SD");
  for (const auto& s : j.value("sensors", nlohmann::json::array())) {
    std::printf("%-16s %-12s %-10s %8.1f %9.1f %7llu %7llu %5s %5s %9.3f %8.1f\n",
                s.value("name", std::string()).c_str(), s.value("segment", std::string()).c_str(),
                s.value("state", std::string()).c_str(), s.value("rate_hz", 0.0),
                s.value("age_ms", 0.0), static_cast<unsigned long long>(s.value("drops", 0ull)),
                static_cast<unsigned long long>(s.value("errors", 0ull)),
                s.value("at_rest", false) ? "rest" : "-",
                s.value("mag_disturbed", false)      ? "dist"
                : s.value("mag_no_reference", false) ? "noref"
                                                     : "ok",
                s.value("gyro_bias_dps", 0.0), s.value("heading_sigma_deg", 0.0));
  }
}

}  // namespace

int main(int argc, char** argv) {
  mocap::CliArgs args;
  args.flag("help", "show this help")
      .flag("version", "print the version")
      .flag("json", "status: print the daemon's JSON reply")
      .option("socket", "control socket (default $XDG_RUNTIME_DIR/mocapd.sock)")
      .option("timeout-ms", "how long to wait for the reply (default 5000)");
  if (!args.parse(argc, argv)) {
    std::fprintf(stderr, "mocapctl: %s\n", args.error().c_str());
    return 2;
  }
  if (args.has("version")) {
    std::printf("mocapctl 0.1.0\n");
    return 0;
  }
  const auto& pos = args.positional();
  if (args.has("help") || pos.empty()) {
    std::printf("%s%s", kUsage, args.help().c_str());
    return args.has("help") ? 0 : 2;
  }
  std::string line;
  for (const auto& p : pos)
    line += (line.empty() ? "" : " ") + p;
  std::string err;
  auto req = mocap::daemon::parse_control_request(line, err);
  if (!req) {
    std::fprintf(stderr, "mocapctl: %s\n%s", err.c_str(), kUsage);
    return 2;
  }
  long timeout = 5000;
  if (!args.get_int("timeout-ms", timeout)) {
    std::fprintf(stderr, "mocapctl: %s\n", args.error().c_str());
    return 2;
  }
  std::string reply;
  try {
    const std::string path =
        args.has("socket") ? *args.get("socket") : mocap::daemon::default_control_socket();
    reply = mocap::daemon::control_call(path, mocap::daemon::format_control_request(*req),
                                        static_cast<int>(timeout));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mocapctl: %s\n", e.what());
    return 1;
  }
  nlohmann::json j = nlohmann::json::parse(reply, nullptr, false);
  if (j.is_discarded() || !j.is_object()) {
    std::fprintf(stderr, "mocapctl: unreadable reply from mocapd: %s\n", reply.c_str());
    return 1;
  }
  if (!j.value("ok", false)) {
    std::fprintf(stderr, "mocapctl: %s\n", j.value("error", std::string("failed")).c_str());
    return 1;
  }
  if (req->command == mocap::daemon::ControlCommand::status && !args.has("json")) {
    print_status_table(j);
  } else if (args.has("json")) {
    std::printf("%s\n", reply.c_str());
  } else {
    std::string msg = j.value("message", std::string("ok"));
    if (j.contains("file")) msg += (msg == "ok" ? ": " : " ") + j["file"].get<std::string>();
    std::printf("%s\n", msg.c_str());
  }
  return 0;
}
