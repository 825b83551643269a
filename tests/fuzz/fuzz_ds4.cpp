// libFuzzer target: the ds4 decoder on arbitrary HID reports (input: [length][report]...).
#include "fuzz_decoder.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return mocap::fuzz::fuzz_decoder("ds4", data, size, true);
}
