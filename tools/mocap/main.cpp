// mocap: offline tool. One subcommand per file (cmd_*.cpp), each declaring its own options.
#include "commands.hpp"
#include "mocap/core/cli.hpp"

int main(int argc, char** argv) {
  CLI::App app{"mocap: offline tool of the mocap motion-capture system", "mocap"};
  mocap::cli::setup_program(app);
  app.require_subcommand(1);
  int exit_code = 0;
  using namespace mocap::cmd;
  for (auto add : {add_filter, add_simulate, add_perform, add_replay, add_export, add_devices,
                   add_bench, add_evaluate, add_gyro_scale, add_score, add_setup, add_stills})
    add(app, exit_code);
  app.footer("'mocap COMMAND --help' describes a command.");  // after: not inherited
  if (auto done = mocap::cli::parse(app, argc, argv)) return *done;
  return exit_code;
}
