// mocapctl: control client for a running mocapd (talks over its Unix-domain control socket).
//   mocapctl [--socket PATH] [--json] status | calibrate [npose|tpose|mounting] | reset-heading |
//            record start [NAME] | record stop | quit
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "mocap/core/cli.hpp"
#include "mocap/daemon/config.hpp"
#include "mocap/daemon/control.hpp"

namespace {

/// mocapctl's command line: global options and one subcommand per control command, all
/// declared in declare_options(); `line` is the control request the parsed command stands for.
struct Options {
  bool json = false;
  std::string socket;
  int timeout_ms = 5000;
  std::string pose, record_name;
  std::string line;
};

void declare_options(CLI::App& app, Options& o) {
  app.add_flag("--json", o.json, "print the daemon's JSON reply (status: instead of the table)");
  app.add_option("--socket", o.socket, "control socket (default $XDG_RUNTIME_DIR/mocapd.sock)");
  app.add_option("--timeout-ms", o.timeout_ms, "how long to wait for the reply, ms")
      ->check(CLI::Range(1, 3600000));
  app.require_subcommand(1);
  namespace cli = mocap::cli;
  cli::add_command(app, "status", "sensors, rates, drops, filter and calibration state")
      ->callback([&o] { o.line = "status"; });
  CLI::App* cal = cli::add_command(
      app, "calibrate",
      "start a calibration (countdown, then hold the pose); no POSE: the daemon's configured "
      "calibration.pose; mounting: an N-pose, then bow and bend the knees twice with the elbows "
      "curling (each sensor's mounting found from its tilt, docs/skeleton.md)");
  cal->add_option("POSE", o.pose, "npose, tpose or mounting")
      ->check(CLI::IsMember({"npose", "tpose", "mounting"}));
  cal->callback([&o] { o.line = o.pose.empty() ? "calibrate" : "calibrate " + o.pose; });
  cli::add_command(app, "reset-heading", "re-align the heading (stand upright facing forward)")
      ->callback([&o] { o.line = "reset-heading"; });
  CLI::App* rec = cli::add_command(app, "record", "start or stop recording a session");
  rec->require_subcommand(1);
  CLI::App* start = cli::add_command(
      *rec, "start",
      "record into a new file NAME inside the daemon's recording.directory (never overwritten: "
      "an existing file is an error); no NAME: a fresh take-YYYYMMDD-HHMMSS.mocapses");
  start->add_option("NAME", o.record_name, "file name of the take");
  start->callback(
      [&o] { o.line = o.record_name.empty() ? "record start" : "record start " + o.record_name; });
  cli::add_command(*rec, "stop",
                   "close the recording; prints duration, frames, samples, drops, bytes")
      ->callback([&o] { o.line = "record stop"; });
  cli::add_command(app, "quit", "stop the daemon")->callback([&o] { o.line = "quit"; });
}

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
  std::printf("%-16s %-12s %-10s %8s %9s %7s %7s %5s %5s %9s %8s  %s\n", "SENSOR", "SEGMENT",
              "STATE", "RATE_HZ", "AGE_MS", "DROPS", "ERRORS", "REST", "MAG", "BIAS_DPS", "HDG_SD",
              "MOUNTING");
  for (const auto& s : j.value("sensors", nlohmann::json::array())) {
    // Its mounting's source and one-sigma ("none": found from motion later).
    std::string mounting = "-";
    if (const auto m = s.find("mounting"); m != s.end() && m->is_object()) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%s +-%.0f deg", m->value("source", std::string()).c_str(),
                    m->value("sigma_deg", 0.0));
      mounting = m->value("source", std::string()) == "none" ? "none (from motion)" : buf;
    }
    std::printf("%-16s %-12s %-10s %8.1f %9.1f %7llu %7llu %5s %5s %9.3f %8.1f  %s\n",
                s.value("name", std::string()).c_str(), s.value("segment", std::string()).c_str(),
                s.value("state", std::string()).c_str(), s.value("rate_hz", 0.0),
                s.value("age_ms", 0.0), static_cast<unsigned long long>(s.value("drops", 0ull)),
                static_cast<unsigned long long>(s.value("errors", 0ull)),
                s.value("at_rest", false) ? "rest" : "-",
                s.value("mag_disturbed", false)      ? "dist"
                : s.value("mag_no_reference", false) ? "noref"
                                                     : "ok",
                s.value("gyro_bias_dps", 0.0), s.value("heading_sigma_deg", 0.0), mounting.c_str());
  }
  // What trackers report about themselves (SlimeVR: battery, signal, temperature, identity),
  // one line per sensor that reported anything.
  for (const auto& s : j.value("sensors", nlohmann::json::array())) {
    std::string line;
    const auto part = [&](const std::string& p) { line += (line.empty() ? "" : ", ") + p; };
    const auto num = [&](const char* key, const char* fmt) {
      if (!s.contains(key) || !s[key].is_number()) return;
      char buf[48];
      std::snprintf(buf, sizeof buf, fmt, s[key].get<double>());
      part(buf);
    };
    std::string who = s.value("board", std::string());
    for (const char* k : {"imu", "mcu"})
      if (s.contains(k)) who += (who.empty() ? "" : " ") + s[k].get<std::string>();
    if (s.contains("firmware"))
      who += (who.empty() ? "" : " ") + ("firmware " + s["firmware"].get<std::string>());
    if (s.contains("address")) who += (who.empty() ? "" : " ") + s["address"].get<std::string>();
    if (!who.empty()) part(who);
    num("battery_pct", "battery %.0f %%");
    num("battery_v", "%.2f V");
    num("battery_runtime_s", "%.0f s left");
    num("rssi_dbm", "signal %.0f dBm");
    num("packet_loss_pct", "%.1f %% packets lost");
    num("temperature_c", "%.1f C");
    if (!line.empty())
      std::printf("%s: %s\n", s.value("name", std::string()).c_str(), line.c_str());
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"mocapctl: control client for a running mocapd", "mocapctl"};
  mocap::cli::setup_program(app);
  Options o;
  declare_options(app, o);
  if (auto done = mocap::cli::parse(app, argc, argv)) return *done;
  std::string err;
  auto req = mocap::daemon::parse_control_request(o.line, err);
  if (!req) {
    std::fprintf(stderr, "mocapctl: %s\n", err.c_str());
    return 2;
  }
  std::string reply;
  try {
    const std::string path = o.socket.empty() ? mocap::daemon::default_control_socket() : o.socket;
    reply = mocap::daemon::control_call(path, mocap::daemon::format_control_request(*req),
                                        o.timeout_ms);
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
  if (req->command == mocap::daemon::ControlCommand::status && !o.json) {
    print_status_table(j);
  } else if (o.json) {
    std::printf("%s\n", reply.c_str());
  } else {
    std::string msg = j.value("message", std::string("ok"));
    if (j.contains("file")) msg += (msg == "ok" ? ": " : " ") + j["file"].get<std::string>();
    std::printf("%s\n", msg.c_str());
  }
  return 0;
}
