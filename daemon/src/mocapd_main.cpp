// mocapd: the motion-capture daemon. Entry point; the daemon itself lives in mocap_daemon.
#include <cstdio>

#include "mocap/core/cli_args.hpp"

int main(int argc, char** argv) {
  mocap::CliArgs args;
  args.flag("help", "show this help").flag("version", "print the version");
  if (!args.parse(argc, argv)) {
    std::fprintf(stderr, "mocapd: %s\n", args.error().c_str());
    return 2;
  }
  if (args.has("version")) {
    std::printf("mocapd 0.1.0\n");
    return 0;
  }
  std::printf("usage: mocapd [options]\n%s", args.help().c_str());
  return args.has("help") ? 0 : 2;
}
