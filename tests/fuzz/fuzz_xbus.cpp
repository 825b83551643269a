// libFuzzer target: the xbus decoder (framing, parsing, units, time mapping) on arbitrary bytes.
#include "fuzz_decoder.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return mocap::fuzz::fuzz_decoder("xbus", data, size, false);
}
