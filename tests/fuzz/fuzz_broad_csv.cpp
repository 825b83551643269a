// libFuzzer target for the BROAD CSV reader: any bytes must parse or fail with a message, and
// whatever parses must run through the attitude filter without non-finite output.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "mocap/eval/broad_csv.hpp"
#include "mocap/eval/run_trial.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  mocap::BroadTrial trial;
  std::string error;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  if (!mocap::parse_broad_csv(text, trial, error)) {
    if (error.empty()) __builtin_trap();  // a failure must say what is wrong
    return 0;
  }
  if (trial.size() == 0 || trial.gyr_rad_s.size() != trial.size()) __builtin_trap();
  if (trial.size() > 2000) return 0;
  mocap::AttitudeFilter f;
  for (size_t i = 0; i < trial.size(); ++i) {
    f.update(mocap::trial_sample(trial, i, mocap::FilterMode::k9d));
    if (!f.output().q_earth_sensor.coeffs().allFinite()) __builtin_trap();
  }
  return 0;
}
