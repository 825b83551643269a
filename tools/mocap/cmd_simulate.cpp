// mocap simulate: emulates a sensor. Emits a protocol's exact bytes for a known motion on a
// pseudo-terminal (printing its path), as UDP datagrams, or into a capture file, and answers
// configuration commands the way the device does. Built on mocap/devsim/sim_device.hpp.
#include <signal.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>

#include "commands.hpp"
#include "mocap/core/cli.hpp"
#include "mocap/devsim/sim_device.hpp"
#include "mocap/devsim/sim_slimevr.hpp"

namespace mocap::cmd {

namespace {

constexpr const char* kSimulateUsage =
    "  --pty prints the slave path (\"pty: /dev/pts/N\") and runs until interrupted.\n"
    "  --out writes a capture: the byte stream, or for HID protocols each report prefixed by\n"
    "  one length byte (the format the fuzz corpora and report-byte tests use).\n"
    "  slimevr: a tracker board speaking to the server at --udp HOST:PORT (handshake, then\n"
    "  rotation + acceleration); --option mac=AA:BB:CC:DD:EE:FF, --option sensors=N (IMUs);\n"
    "  what it reports about itself once a second: --option battery_v=V, battery_pct=0..100,\n"
    "  rssi=DBM, temperature=C.\n";

bool parse_kv(const std::vector<std::string>& items, std::map<std::string, std::string>& out) {
  for (const auto& kv : items) {
    const auto eq = kv.find('=');
    if (eq == std::string::npos || eq == 0) {
      std::fprintf(stderr, "mocap simulate: --option '%s' must be KEY=VALUE\n", kv.c_str());
      return false;
    }
    out[kv.substr(0, eq)] = kv.substr(eq + 1);
  }
  return true;
}

int write_capture(const std::string& protocol, const std::string& motion_spec, double rate,
                  const std::map<std::string, std::string>& options, long samples,
                  const std::string& path) {
  auto motion = make_motion(motion_spec);
  auto enc = make_encoder(protocol, {.rate_hz = rate, .options = options});
  std::vector<uint8_t> out, file;
  if (enc->report_size() > 0) {  // HID: the calibration report first, as the driver reads it
    for (uint8_t id : {0x02, 0x05}) {
      out.clear();
      if (enc->feature_report(id, out)) {
        file.push_back(static_cast<uint8_t>(out.size()));
        file.insert(file.end(), out.begin(), out.end());
        break;
      }
    }
  }
  const int64_t period = static_cast<int64_t>(1e9 / rate);
  for (long i = 0; i < samples; ++i) {
    out.clear();
    enc->encode(motion->at(i * period), out);
    const std::size_t rs = enc->report_size();
    if (rs == 0) {
      file.insert(file.end(), out.begin(), out.end());
    } else {
      for (std::size_t o = 0; o + rs <= out.size(); o += rs) {
        file.push_back(static_cast<uint8_t>(rs));
        file.insert(file.end(), out.begin() + o, out.begin() + o + rs);
      }
    }
  }
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(file.data()), static_cast<std::streamsize>(file.size()));
  if (!f) {
    std::fprintf(stderr, "mocap simulate: cannot write %s\n", path.c_str());
    return 1;
  }
  std::printf("wrote %zu bytes (%ld samples of %s) to %s\n", file.size(), samples, protocol.c_str(),
              path.c_str());
  return 0;
}

/// Returns after duration_s (0: never) or when one of the (blocked) stop signals arrives.
void wait_for_stop(const sigset_t& stop_signals, double duration_s) {
  const timespec ts{static_cast<time_t>(duration_s),
                    static_cast<long>((duration_s - static_cast<time_t>(duration_s)) * 1e9)};
  if (duration_s > 0)
    sigtimedwait(&stop_signals, nullptr, &ts);
  else
    sigwaitinfo(&stop_signals, nullptr);
}

/// A SlimeVR tracker board: its own connection logic over UDP (not SimulatedDevice's one-way
/// stream), until the duration passes or a stop signal arrives.
int run_slimevr(const SimOptions& so, double duration, const sigset_t& stop_signals) {
  if (so.udp.empty()) {
    std::fprintf(stderr, "mocap simulate: slimevr trackers talk UDP: give --udp HOST:PORT\n");
    return 2;
  }
  SimSlimeOptions o;
  o.server = so.udp;
  o.rate_hz = so.rate_hz;
  o.motion = so.motion;
  for (const auto& [k, v] : so.options) {
    double x = 0;
    const bool number = [&] {
      std::size_t used = 0;
      try {
        x = std::stod(v, &used);
      } catch (const std::exception&) {
        return false;
      }
      return used == v.size();
    }();
    if (k != "mac" && !number) {
      std::fprintf(stderr, "mocap simulate: --option %s=%s: not a number\n", k.c_str(), v.c_str());
      return 2;
    }
    if (k == "mac") {
      o.mac = v;
    } else if (k == "sensors") {
      if (x != std::floor(x) || x < 1 || x > 10) {
        std::fprintf(stderr, "mocap simulate: --option sensors=%s: 1..10 IMUs\n", v.c_str());
        return 2;
      }
      o.sensors = static_cast<int>(x);
    } else if (k == "battery_v") {
      o.battery_v = x;
    } else if (k == "battery_pct") {
      o.battery_pct = x;
    } else if (k == "rssi") {
      o.rssi_dbm = x;
    } else if (k == "temperature") {
      o.temperature_c = x;
    } else {
      std::fprintf(stderr,
                   "mocap simulate: slimevr has no option '%s' (mac, sensors, battery_v, "
                   "battery_pct, rssi, temperature)\n",
                   k.c_str());
      return 2;
    }
  }
  std::unique_ptr<SimSlimeTracker> made;
  try {
    made = std::make_unique<SimSlimeTracker>(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mocap simulate: slimevr: %s\n", e.what());
    return 2;
  }
  SimSlimeTracker& t = *made;
  std::printf("udp: slimevr tracker %s (%d sensors) to %s\n", o.mac.c_str(), o.sensors,
              o.server.c_str());
  std::fflush(stdout);
  t.start();
  wait_for_stop(stop_signals, duration);
  t.stop();
  std::fprintf(stderr, "mocap simulate: sent %llu samples per sensor (%s, %llu handshakes)\n",
               static_cast<unsigned long long>(t.samples()),
               t.connected() ? "connected" : "never answered",
               static_cast<unsigned long long>(t.handshakes()));
  return 0;
}

/// mocap simulate's command line (declared in add_simulate).
struct SimulateOptions {
  SimOptions sim;
  bool pty = false;
  std::string out;
  long samples = 1000;
  double duration_s = 0;
  std::vector<std::string> options;
};

int run_simulate(SimulateOptions& o) {
  SimOptions& so = o.sim;
  const double duration = o.duration_s;
  if (!parse_kv(o.options, so.options)) return 2;
  try {
    if (!o.out.empty())
      return write_capture(so.protocol, so.motion, so.rate_hz, so.options, o.samples, o.out);
    // Block the stop signals before threads start, then wait for them synchronously.
    sigset_t stop_signals;
    sigemptyset(&stop_signals);
    sigaddset(&stop_signals, SIGINT);
    sigaddset(&stop_signals, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
    if (so.protocol == "slimevr") return run_slimevr(so, duration, stop_signals);
    SimulatedDevice sim(so);
    if (so.udp.empty())
      std::printf("pty: %s\n", sim.path().c_str());
    else
      std::printf("udp: sending %s to %s\n", so.protocol.c_str(), so.udp.c_str());
    std::fflush(stdout);
    sim.start();
    wait_for_stop(stop_signals, duration);
    sim.stop();
    std::fprintf(stderr, "mocap simulate: sent %llu samples (%llu withheld)\n",
                 static_cast<unsigned long long>(sim.samples()),
                 static_cast<unsigned long long>(sim.dropped()));
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mocap simulate: %s\n", e.what());
    return 1;
  }
}

}  // namespace

void add_simulate(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<SimulateOptions>();
  o->sim.motion = "rotate";
  CLI::App* c = cli::add_command(app, "simulate",
                                 "emulate a device: protocol bytes on a pty, as UDP or to a file");
  c->footer(kSimulateUsage);
  c->add_option("--protocol", o->sim.protocol, "witmotion|xbus|ds4|dualsense|joycon|line|slimevr")
      ->required();
  CLI::Option* pty = c->add_flag(
      "--pty", o->pty, "emit on a new pseudo-terminal (one destination: --pty, --udp or --out)");
  c->add_option("--link", o->sim.pty_link, "also make a stable symlink at PATH to the --pty")
      ->needs(pty);
  CLI::Option* udp = c->add_option(
      "--udp", o->sim.udp, "send datagrams to HOST:PORT (one destination: --pty, --udp or --out)");
  CLI::Option* out = c->add_option("--out", o->out,
                                   "write a capture file (one destination: --pty, --udp or --out)");
  // One destination: the bytes go to a pty, to UDP or into a file.
  pty->excludes(udp)->excludes(out);
  udp->excludes(out);
  c->add_option("--samples", o->samples, "number of samples written to the --out file")
      ->check(CLI::PositiveNumber)
      ->needs(out);
  c->add_option("--motion", o->sim.motion, "static|rotate|FILE.csv");
  c->add_option("--rate", o->sim.rate_hz, "output rate, Hz")->check(CLI::PositiveNumber);
  c->add_option("--duration", o->duration_s, "stop after this many seconds (0: until interrupted)")
      ->check(CLI::NonNegativeNumber);
  cli::add_multi(*c, "--option", o->options, "protocol option KEY=VALUE (e.g. quat_order=xyzw)");
  c->callback([o, &exit_code] {
    if (!o->pty && o->sim.udp.empty() && o->out.empty()) {
      std::fprintf(stderr, "mocap simulate: give one of --pty, --udp, --out\n%s", kSimulateUsage);
      exit_code = 2;
      return;
    }
    exit_code = run_simulate(*o);
  });
}

}  // namespace mocap::cmd
