// The sensors `mocap setup` can hear (see candidates.hpp).
#include "mocap/setup/candidates.hpp"

#include <algorithm>
#include <stdexcept>

#include "mocap/drivers/known_devices.hpp"
#include "mocap/drivers/slimevr_listen.hpp"

namespace mocap::setup {
namespace {

/// WitMotion at the example rigs' 115200 baud and 100 Hz, at its factory 9600, then a DIY
/// board's line protocol: what a generic USB-serial chip may carry.
std::vector<Probe> generic_serial_probes() {
  return {{"witmotion", 115200, 100}, {"witmotion", 9600, 0}, {"line", 115200, 0}};
}

/// A driver named by the user: the settings the example rigs use with it.
std::vector<Probe> driver_probes(const std::string& driver) {
  if (driver == "witmotion") return {{"witmotion", 115200, 100}, {"witmotion", 9600, 0}};
  if (driver == "line") return {{"line", 115200, 0}};
  if (driver == "xbus") return {{"xbus", 115200, 0}};
  if (driver == "ds4" || driver == "dualsense" || driver == "joycon") return {{driver, 0, 0}};
  throw std::invalid_argument("unknown driver '" + driver +
                              "' (setup probes witmotion, line, xbus, ds4, dualsense, joycon)");
}

}  // namespace

void apply_probe(Candidate& c) {
  const Probe& p = c.probes.at(c.probe);
  c.sensor.driver = p.driver;
  c.sensor.baud = p.baud;
  c.sensor.rate_hz = p.rate_hz;
}

Candidate port_candidate(const std::string& spec) {
  Candidate c;
  const auto at = spec.rfind('@');
  const std::string path = at == std::string::npos ? spec : spec.substr(0, at);
  if (path.empty()) throw std::invalid_argument("--port '" + spec + "': no path");
  c.sensor.port = path;
  if (at == std::string::npos) {
    c.probes = generic_serial_probes();
    c.what = "serial port " + path;
  } else {
    c.probes = driver_probes(spec.substr(at + 1));
    c.what = spec.substr(at + 1) + " at " + path;
  }
  apply_probe(c);
  return c;
}

std::vector<Candidate> find_candidates(const FindOptions& o, std::vector<std::string>& notes) {
  std::vector<Candidate> out;
  if (o.scan) {
    for (const FoundDevice& f : find_devices()) {
      const std::string proto = f.known->protocol;
      const std::string where = f.known->what + std::string(" at ") + f.path +
                                (f.serial.empty() ? "" : ", serial " + f.serial);
      if (proto == "slimevr_hid") {
        notes.push_back(where +
                        ": its trackers are not assigned by `mocap setup` (each needs its "
                        "address: `mocapctl status` lists them; docs/devices.md)");
        continue;
      }
      Candidate c;
      c.what = where;
      if (f.transport == "hid") {
        c.sensor.vid = f.known->vid;
        c.sensor.pid = f.known->pid;
        c.sensor.hid = true;
        c.sensor.serial = f.serial;
      } else {
        c.sensor.port = f.port;
      }
      c.probes =
          proto.find('|') != std::string::npos ? generic_serial_probes() : driver_probes(proto);
      apply_probe(c);
      out.push_back(std::move(c));
    }
  }
  for (const std::string& p : o.ports) {
    try {
      out.push_back(port_candidate(p));
    } catch (const std::invalid_argument& e) {
      notes.push_back(e.what());
    }
  }
  if (!o.slimevr.empty() && o.slimevr_listen_s > 0) {
    std::string err;
    auto hellos =
        listen_slimevr_hellos(o.slimevr, static_cast<int>(o.slimevr_listen_s * 1000), err);
    std::sort(hellos.begin(), hellos.end(),  // listed by MAC, not by who spoke first
              [](const SlimeVrHello& a, const SlimeVrHello& b) { return a.mac < b.mac; });
    if (!err.empty())
      notes.push_back("SlimeVR: cannot listen on udp " + o.slimevr + " (" + err +
                      "); is mocapd running? Stop it during setup");
    for (const SlimeVrHello& h : hellos) {
      for (int k = 0; k < o.slimevr_imus; ++k) {
        Candidate c;
        c.sensor.port = "udp:" + o.slimevr;
        c.sensor.options = {{"mac", h.mac}, {"tracker", std::to_string(k)}};
        c.probes = {{"slimevr", 0, 0}};
        c.what = "SlimeVR tracker " + h.mac + (k == 0 ? "" : " IMU " + std::to_string(k)) + " at " +
                 h.ip;
        c.optional = k > 0;
        apply_probe(c);
        out.push_back(std::move(c));
      }
    }
  }
  return out;
}

}  // namespace mocap::setup
