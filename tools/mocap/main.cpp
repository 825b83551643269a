// mocap: offline tool. Dispatches to one subcommand per file (cmd_*.cpp).
#include <cstdio>
#include <string_view>

#include "commands.hpp"

namespace {

struct Command {
  std::string_view name;
  int (*run)(int, char**);
  std::string_view summary;
};

constexpr Command kCommands[] = {
    {"filter", mocap::cmd::run_filter, "run an attitude filter over a CSV of IMU samples"},
    {"simulate", mocap::cmd::run_simulate, "emulate a device: protocol bytes on a pty or UDP"},
    {"perform", mocap::cmd::run_perform,
     "run the virtual performer: its samples, ground truth and BVH to files"},
    {"replay", mocap::cmd::run_replay, "run a session or sample CSV through the pipeline offline"},
    {"export", mocap::cmd::run_export, "convert a recorded session to BVH or CSV"},
    {"devices", mocap::cmd::run_devices, "list connected devices that a driver supports"},
    {"bench", mocap::cmd::run_bench, "benchmarks (filter, skeleton, latency, capacity, ...)"},
    {"evaluate", mocap::cmd::run_evaluate, "score attitude filters on the BROAD trials"},
    {"gyro-scale", mocap::cmd::run_gyro_scale,
     "each sensor's gyro scale from table spins (a one-time calibration)"},
    {"score", mocap::cmd::run_score,
     "full-body metric of a pose CSV against a truth CSV (datasets/cmu/README.md)"},
};

void usage(FILE* out) {
  std::fprintf(out, "usage: mocap COMMAND [ARGS...]\n\ncommands:\n");
  for (const auto& c : kCommands)
    std::fprintf(out, "  %-10.*s %.*s\n", static_cast<int>(c.name.size()), c.name.data(),
                 static_cast<int>(c.summary.size()), c.summary.data());
  std::fprintf(out, "\n'mocap COMMAND --help' describes a command.\n");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    usage(stderr);
    return 2;
  }
  std::string_view name = argv[1];
  if (name == "--help" || name == "-h" || name == "help") {
    usage(stdout);
    return 0;
  }
  for (const auto& c : kCommands)
    if (c.name == name) return c.run(argc - 1, argv + 1);
  std::fprintf(stderr, "mocap: unknown command '%s'\n", argv[1]);
  usage(stderr);
  return 2;
}
