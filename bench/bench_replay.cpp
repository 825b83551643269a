// mocap bench replay: not yet implemented (placeholder replaced by its issue's work).
#include <cstdio>

#include "bench.hpp"

namespace mocap::bench {

int run_replay(int, char**) {
  std::fprintf(stderr, "mocap bench replay: not implemented yet\n");
  return 2;
}

}  // namespace mocap::bench
