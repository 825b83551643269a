// mocap evaluate: not yet implemented (placeholder replaced by its issue's work).
#include <cstdio>

#include "commands.hpp"

namespace mocap::cmd {

int run_evaluate(int, char**) {
  std::fprintf(stderr, "mocap evaluate: not implemented yet\n");
  return 2;
}

}  // namespace mocap::cmd
