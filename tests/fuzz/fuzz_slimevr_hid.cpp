// libFuzzer target: the SlimeVR HID receiver's report parser on the whole input, and its
// decoder (register packets, address mapping, appear/leave) on the input as [len][report]...
#include "fuzz_decoder.hpp"
#include "mocap/drivers/slimevr_hid.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::array<mocap::slimevr_hid::Packet, mocap::slimevr_hid::kMaxPackets> packets;
  if (mocap::slimevr_hid::parse_report(std::span(data, size), packets) > packets.size())
    __builtin_trap();
  mocap::DeviceSpec spec;
  spec.name = "fuzz";
  spec.protocol = "slimevr_hid";
  spec.options["trackers"] = "02:5E:00:00:00:A0/0=0;02:5E:00:00:00:A1/0=1@-y,x,z";
  return mocap::fuzz::fuzz_decoder(spec, data, size, true,
                                   400'000'000);  // long steps: trackers leave and come back
}
