// Test helpers shared by the SlimeVR tests: a recorded UDP datagram as the decoder reads it
// (sender IPv4 address and port, big-endian, then the payload), and a receiver dongle's decoder
// with two trackers mapped.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "mocap/drivers/device.hpp"

namespace mocap::test {

inline std::vector<uint8_t> slimevr_record(const std::vector<uint8_t>& datagram,
                                           uint32_t ip = 0x7f000001, uint16_t port = 40000) {
  std::vector<uint8_t> r = {static_cast<uint8_t>(ip >> 24),  static_cast<uint8_t>(ip >> 16),
                            static_cast<uint8_t>(ip >> 8),   static_cast<uint8_t>(ip),
                            static_cast<uint8_t>(port >> 8), static_cast<uint8_t>(port)};
  r.insert(r.end(), datagram.begin(), datagram.end());
  return r;
}

/// A SlimeVR decoder ("slimevr": UDP, "slimevr_hid": the receiver dongle) with the `trackers`
/// option (MAC/sensor id = rig sensor, as in a rig file).
inline std::unique_ptr<StreamDecoder> slimevr_decoder(const char* protocol, const char* trackers) {
  DeviceSpec spec;
  spec.name = "slime";
  spec.protocol = protocol;
  if (std::string(protocol) == "slimevr_hid") spec.port = "hid:1209:7690";
  spec.options["trackers"] = trackers;
  return make_decoder(spec);
}

/// The receiver dongle's decoder, trackers ...:A0 sensor 0 -> rig sensor 4, ...:A1 -> 5.
inline std::unique_ptr<StreamDecoder> slimevr_dongle_decoder() {
  return slimevr_decoder("slimevr_hid", "02:5E:00:00:00:A0/0=4;02:5E:00:00:00:A1/0=5");
}

}  // namespace mocap::test
