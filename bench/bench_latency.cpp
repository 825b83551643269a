// mocap bench latency: not yet implemented (placeholder replaced by its issue's work).
#include <cstdio>

#include "bench.hpp"

namespace mocap::bench {

int run_latency(int, char**) {
  std::fprintf(stderr, "mocap bench latency: not implemented yet\n");
  return 2;
}

}  // namespace mocap::bench
