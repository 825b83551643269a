// libFuzzer target for the skeleton's TOML parsers (calibration, body model, joint limits): any
// bytes parse or fail with a message; a calibration that parses serialises and parses back to the
// same text; parsed limits are valid.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

#include "mocap/skeleton/body_model.hpp"
#include "mocap/skeleton/calibration.hpp"
#include "mocap/skeleton/joint_limits.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const mocap::Calibration c = mocap::parse_calibration(text, "fuzz");
    const std::string s = mocap::serialize_calibration(c);
    if (mocap::serialize_calibration(mocap::parse_calibration(s, "again")) != s) __builtin_trap();
  } catch (const std::runtime_error& e) {
    if (std::string_view(e.what()).empty()) __builtin_trap();
  }
  try {
    const mocap::BodyModel m(mocap::parse_body_config(text, "fuzz"));
    if (!(m.height_m() > 0)) __builtin_trap();
  } catch (const std::runtime_error& e) {
    if (std::string_view(e.what()).empty()) __builtin_trap();
  }
  try {
    mocap::validate(mocap::parse_joint_limits(text, "fuzz"));
  } catch (const std::runtime_error& e) {
    if (std::string_view(e.what()).empty()) __builtin_trap();
  } catch (const std::invalid_argument&) {
    __builtin_trap();  // parse_joint_limits must only return valid limits
  }
  return 0;
}
