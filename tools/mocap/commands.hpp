// The mocap tool's subcommands. Each cmd_<name>.cpp declares its subcommand and every option of
// it in `add_<name>(app, exit_code)` (one Options struct per command, filled by CLI11); the
// subcommand's callback runs it and stores the process exit code (0 ok, 1 failure, 2 usage).
#pragma once

#include <CLI/CLI.hpp>

namespace mocap::cmd {

void add_filter(CLI::App& app, int& exit_code);
void add_simulate(CLI::App& app, int& exit_code);
void add_perform(CLI::App& app, int& exit_code);
void add_replay(CLI::App& app, int& exit_code);
void add_export(CLI::App& app, int& exit_code);
void add_devices(CLI::App& app, int& exit_code);
void add_bench(CLI::App& app, int& exit_code);
void add_evaluate(CLI::App& app, int& exit_code);
void add_gyro_scale(CLI::App& app, int& exit_code);
void add_score(CLI::App& app, int& exit_code);
void add_setup(CLI::App& app, int& exit_code);
void add_stills(CLI::App& app, int& exit_code);

}  // namespace mocap::cmd
