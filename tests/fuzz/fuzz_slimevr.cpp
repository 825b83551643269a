// libFuzzer target: the SlimeVR UDP parser on the whole input as one datagram, and the SlimeVR
// decoder (boards, packet numbers, replies, mapping) on the input as [len][record]... where a
// record is a 6-byte tracker address then a datagram (what the device records).
#include "fuzz_decoder.hpp"
#include "mocap/drivers/slimevr.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::array<mocap::slimevr::Packet, mocap::slimevr::kMaxPackets> packets;
  mocap::slimevr::Error err;
  const std::size_t n = mocap::slimevr::parse_datagram(std::span(data, size), packets, err);
  if (n > packets.size()) __builtin_trap();
  mocap::DeviceSpec spec;
  spec.name = "fuzz";
  spec.protocol = "slimevr";
  spec.options["trackers"] =
      "02:5E:00:00:00:01/0=0;02:5E:00:00:00:01/1=1@-y,x,z;00:00:00:00:00:00/0=2";
  return mocap::fuzz::fuzz_decoder(spec, data, size, true);
}
