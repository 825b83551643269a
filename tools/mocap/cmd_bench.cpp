// mocap bench NAME: the benchmark bodies in bench/, one subcommand each.
#include "bench.hpp"
#include "commands.hpp"
#include "mocap/core/cli.hpp"

namespace mocap::cmd {

void add_bench(CLI::App& app, int& exit_code) {
  CLI::App* b = cli::add_command(app, "bench",
                                 "benchmarks (filter, skeleton, accuracy, latency, capacity, "
                                 "replay, record); each prints JSON");
  b->require_subcommand(1);
  for (auto add : {bench::add_filter, bench::add_skeleton, bench::add_accuracy, bench::add_latency,
                   bench::add_capacity, bench::add_replay, bench::add_record})
    add(*b, exit_code);
}

}  // namespace mocap::cmd
