// Benchmarks run by `mocap bench NAME [ARGS]`. Each prints one JSON object on stdout and returns
// the exit code. Timings are reported with a baseline measured in the same process (ratios),
// because these machines are shared and noisy. argv[0] is the benchmark name.
#pragma once

namespace mocap::bench {

int run_filter(int argc, char** argv);    // filter: ns/update per algorithm, ratio to Madgwick
int run_skeleton(int argc, char** argv);  // skeleton: FK + limits for the 150-avatar crowd
int run_accuracy(int argc, char** argv);  // accuracy: virtual performer through the pipeline
int run_latency(int argc, char** argv);   // latency: pty bytes -> JSON line over TCP
int run_capacity(int argc, char** argv);  // capacity: sensors x rate without drops, CPU use
int run_replay(int argc, char** argv);    // replay: long session through filter+skeleton+BVH
int run_record(int argc, char** argv);    // record: session block compression, size and CPU

}  // namespace mocap::bench
