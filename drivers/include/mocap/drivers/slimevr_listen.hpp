// Finding SlimeVR trackers on the network (`mocap devices`): listen on the trackers' UDP port
// for a while and report the boards whose handshake broadcast was heard. Passive: nothing is
// answered. The port cannot be shared: while mocapd listens on it, this fails (its status
// names the connected trackers).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace mocap {

struct SlimeVrHello {
  std::string mac;  ///< "AA:BB:CC:DD:EE:FF", the rig's options.mac
  std::string ip;
  uint32_t board = 0, imu = 0, mcu = 0, protocol_version = 0;
  std::string firmware;
};

/// Listens on HOST:PORT (e.g. "0.0.0.0:6969") for ms milliseconds. Empty + err if it cannot
/// bind; empty without err if no tracker said hello.
std::vector<SlimeVrHello> listen_slimevr_hellos(const std::string& host_port, int ms,
                                                std::string& err);

}  // namespace mocap
