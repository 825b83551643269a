// libFuzzer target: the joycon decoder on arbitrary HID reports (input: [length][report]...).
#include "fuzz_decoder.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return mocap::fuzz::fuzz_decoder("joycon", data, size, true);
}
