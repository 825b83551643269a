// mocap bench skeleton: not yet implemented (placeholder replaced by its issue's work).
#include <cstdio>

#include "bench.hpp"

namespace mocap::bench {

int run_skeleton(int, char**) {
  std::fprintf(stderr, "mocap bench skeleton: not implemented yet\n");
  return 2;
}

}  // namespace mocap::bench
