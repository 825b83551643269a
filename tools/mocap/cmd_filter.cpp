// mocap filter: not yet implemented (placeholder replaced by its issue's work).
#include <cstdio>

#include "commands.hpp"

namespace mocap::cmd {

int run_filter(int, char**) {
  std::fprintf(stderr, "mocap filter: not implemented yet\n");
  return 2;
}

}  // namespace mocap::cmd
