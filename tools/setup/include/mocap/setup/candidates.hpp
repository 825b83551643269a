// The sensors `mocap setup` can hear, before any is assigned: the serial, HID and USB devices
// `mocap devices` finds (known USB ids), serial ports named on the command line, and the SlimeVR
// boards heard saying hello on the network. Each becomes one or more candidates: a rig sensor
// without a segment (port or USB ids, options such as a SlimeVR MAC and IMU number) and the ways
// to read it, tried in order until samples arrive (a CH340 adapter may carry a WitMotion at
// 115200 or 9600 baud, or a DIY board's line protocol).
#pragma once

#include <string>
#include <vector>

#include "mocap/daemon/config.hpp"

namespace mocap::setup {

/// One way to read a device: the driver and its serial settings (0: the driver's default).
struct Probe {
  std::string driver;
  int baud = 0;
  double rate_hz = 0;
};

struct Candidate {
  daemon::SensorConfig sensor;  ///< no name, no segment; driver, baud, rate from the probe
  std::vector<Probe> probes;
  std::size_t probe = 0;  ///< the probe in use
  std::string what;       ///< for the user: "WitMotion/DIY serial at /dev/ttyUSB0", ...
  /// A SlimeVR board's further IMU slot (extension port): silent means absent, not worth naming.
  bool optional = false;
};

struct FindOptions {
  bool scan = true;                      ///< enumerate serial, HID and USB devices (known ids)
  std::vector<std::string> ports;        ///< "PATH" (probed) or "PATH@DRIVER"
  std::string slimevr = "0.0.0.0:6969";  ///< where SlimeVR boards send ("" = none)
  double slimevr_listen_s = 2.0;         ///< how long to listen for their hello
  int slimevr_imus = 2;                  ///< IMU slots tried per board (0 main, 1 extension)
};

/// Sets the candidate's driver, baud and rate from its current probe.
void apply_probe(Candidate& c);

/// Every candidate found. Things the user should know (a port that is not understood, a SlimeVR
/// receiver whose trackers setup cannot map, no SlimeVR port) go to `notes`.
std::vector<Candidate> find_candidates(const FindOptions& o, std::vector<std::string>& notes);

/// The probes for a port named as "PATH@DRIVER" or "PATH" (generic serial). Throws
/// std::invalid_argument for an unknown driver.
Candidate port_candidate(const std::string& spec);

}  // namespace mocap::setup
