// The mocap tool's subcommands. Each is `int run_<name>(int argc, char** argv)` in cmd_<name>.cpp,
// where argv[0] is the subcommand name; returns the process exit code (0 ok, 1 failure, 2 usage).
#pragma once

namespace mocap::cmd {

int run_filter(int argc, char** argv);
int run_simulate(int argc, char** argv);
int run_perform(int argc, char** argv);
int run_replay(int argc, char** argv);
int run_export(int argc, char** argv);
int run_devices(int argc, char** argv);
int run_bench(int argc, char** argv);
int run_evaluate(int argc, char** argv);
int run_gyro_scale(int argc, char** argv);
int run_score(int argc, char** argv);

}  // namespace mocap::cmd
