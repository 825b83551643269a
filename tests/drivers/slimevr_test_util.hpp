// Test helper shared by the SlimeVR tests: a recorded UDP datagram as the decoder reads it
// (sender IPv4 address and port, big-endian, then the payload).
#pragma once

#include <cstdint>
#include <vector>

namespace mocap::test {

inline std::vector<uint8_t> slimevr_record(const std::vector<uint8_t>& datagram,
                                           uint32_t ip = 0x7f000001, uint16_t port = 40000) {
  std::vector<uint8_t> r = {static_cast<uint8_t>(ip >> 24),  static_cast<uint8_t>(ip >> 16),
                            static_cast<uint8_t>(ip >> 8),   static_cast<uint8_t>(ip),
                            static_cast<uint8_t>(port >> 8), static_cast<uint8_t>(port)};
  r.insert(r.end(), datagram.begin(), datagram.end());
  return r;
}

}  // namespace mocap::test
