// Shared body of the driver fuzz targets: feeds arbitrary bytes to a protocol decoder in
// input-chosen chunks (or as length-prefixed records for HID protocols) and checks that every
// emitted sample is finite and time never runs backwards.
#pragma once

#include <cstddef>
#include <cstdint>

#include "mocap/drivers/device.hpp"

namespace mocap::fuzz {

class CheckingSink : public SampleSink {
 public:
  void on_sample(const ImuSample& s) override {
    if ((s.has(kFieldGyr) && !s.gyr_rad_s.allFinite()) ||
        (s.has(kFieldAcc) && !s.acc_m_s2.allFinite()) ||
        (s.has(kFieldMag) && !s.mag_uT.allFinite()) || !s.q_device_sensor.coeffs().allFinite() ||
        s.t_host_ns < last_t_)
      __builtin_trap();
    last_t_ = s.t_host_ns;
  }

 private:
  int64_t last_t_ = INT64_MIN;
};

/// Feeds the input to `spec`'s decoder. records = true: input is [len][len bytes]... (one HID
/// report or datagram per record); samples step_ns apart in host time.
inline int fuzz_decoder(const DeviceSpec& spec, const uint8_t* data, std::size_t size, bool records,
                        int64_t step_ns = 4'000'000) {
  auto dec = make_decoder(spec);
  CheckingSink sink;
  std::size_t off = 0;
  int64_t t_ns = 1'000'000'000;
  while (off < size) {
    std::size_t n;
    if (records) {
      n = data[off++];
      if (n > size - off) n = size - off;
    } else {
      n = 1 + data[off] % 97;
      if (n > size - off) n = size - off;
    }
    dec->feed(std::span(data + off, n), t_ns, sink);
    off += n;
    t_ns += step_ns;
  }
  return 0;
}

inline int fuzz_decoder(const char* protocol, const uint8_t* data, std::size_t size, bool records) {
  DeviceSpec spec;
  spec.name = "fuzz";
  spec.protocol = protocol;
  return fuzz_decoder(spec, data, size, records);
}

}  // namespace mocap::fuzz
