// libFuzzer target: the daemon's TOML configuration loader (parse, validate, --set overrides,
// print back). Any input must give a config or errors, never a crash; a config that loads must
// print to TOML that loads again to the same configuration (printed the same).
#include <cstdint>
#include <cstdlib>
#include <string>

#include "mocap/daemon/config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // The first line (if short) is used as a --set override, the rest as the file.
  std::string text(reinterpret_cast<const char*>(data), size);
  std::vector<std::string> sets;
  if (auto nl = text.find('\n');
      nl != std::string::npos && nl < 80 && text.rfind("#set ", 0) == 0) {
    sets.push_back(text.substr(5, nl - 5));
    text = text.substr(nl + 1);
  }
  mocap::daemon::ConfigErrors errs;
  auto cfg = mocap::daemon::parse_config(text, "fuzz.toml", sets, errs);
  if (cfg) {
    const std::string printed = mocap::daemon::config_to_toml(*cfg);
    mocap::daemon::ConfigErrors errs2;
    auto back = mocap::daemon::parse_config(printed, "fuzz.toml", {}, errs2);
    if (!back) std::abort();
    // Exact: the reloaded configuration prints to the same text.
    if (mocap::daemon::config_to_toml(*back) != printed) std::abort();
  } else if (errs.errors.empty()) {
    std::abort();  // a rejected config must say why
  }
  return 0;
}
