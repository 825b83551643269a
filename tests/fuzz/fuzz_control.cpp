// libFuzzer target: the control-socket request parser. Any bytes give a request or an error
// message; a parsed request formats back to a line that parses to the same request.
#include <cstdint>
#include <cstdlib>
#include <string>

#include "mocap/daemon/control.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string line(reinterpret_cast<const char*>(data), size);
  std::string err;
  auto req = mocap::daemon::parse_control_request(line, err);
  if (!req) {
    if (err.empty()) std::abort();
    (void)mocap::daemon::control_error_reply(err);
    return 0;
  }
  const std::string again = mocap::daemon::format_control_request(*req);
  auto req2 = mocap::daemon::parse_control_request(again, err);
  if (!req2 || req2->command != req->command || req2->argument != req->argument) std::abort();
  return 0;
}
