// Benchmarks run by `mocap bench NAME [ARGS]`. Each prints one JSON object on stdout. Timings are
// reported with a baseline measured in the same process (ratios), because these machines are
// shared and noisy. Each add_<name> declares the subcommand NAME and all its options under
// `bench`; its callback runs the benchmark and stores the exit code.
#pragma once

#include <CLI/CLI.hpp>

namespace mocap::bench {

void add_filter(CLI::App& bench, int& exit_code);    // ns/update per algorithm, ratio to Madgwick
void add_skeleton(CLI::App& bench, int& exit_code);  // FK + limits for the 150-avatar crowd
void add_accuracy(CLI::App& bench, int& exit_code);  // virtual performer through the pipeline
void add_latency(CLI::App& bench, int& exit_code);   // pty bytes -> JSON line over TCP
void add_capacity(CLI::App& bench, int& exit_code);  // sensors x rate without drops, CPU use
void add_replay(CLI::App& bench, int& exit_code);    // long session through filter+skeleton+BVH
void add_record(CLI::App& bench, int& exit_code);    // session block compression, size and CPU

}  // namespace mocap::bench
