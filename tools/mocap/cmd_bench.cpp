// mocap bench NAME: dispatches to the benchmark bodies in bench/.
#include <cstdio>
#include <string_view>

#include "bench.hpp"
#include "commands.hpp"

namespace mocap::cmd {

int run_bench(int argc, char** argv) {
  struct Entry {
    std::string_view name;
    int (*run)(int, char**);
  };
  static constexpr Entry kBenches[] = {
      {"filter", bench::run_filter},     {"skeleton", bench::run_skeleton},
      {"accuracy", bench::run_accuracy}, {"latency", bench::run_latency},
      {"capacity", bench::run_capacity}, {"replay", bench::run_replay},
      {"record", bench::run_record},
  };
  if (argc >= 2) {
    for (const auto& b : kBenches)
      if (b.name == argv[1]) return b.run(argc - 1, argv + 1);
  }
  std::fprintf(stderr, "usage: mocap bench NAME [ARGS]\nbenchmarks:");
  for (const auto& b : kBenches)
    std::fprintf(stderr, " %.*s", static_cast<int>(b.name.size()), b.name.data());
  std::fprintf(stderr, "\n");
  return 2;
}

}  // namespace mocap::cmd
