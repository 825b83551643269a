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
  auto dec = mocap::make_decoder(spec);
  mocap::fuzz::CheckingSink sink;
  std::size_t off = 0;
  int64_t t_ns = 1'000'000'000;
  while (off < size) {
    std::size_t len = data[off++];
    if (len > size - off) len = size - off;
    dec->feed(std::span(data + off, len), t_ns, sink);
    off += len;
    t_ns += 400'000'000;  // long steps: trackers leave and come back
  }
  return 0;
}
