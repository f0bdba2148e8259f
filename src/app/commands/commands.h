// The twinsim command-line commands. Each Add*Command registers a CLI11 subcommand
// whose callback does the work and stores the process exit code in *exit_code;
// errors are thrown (core/error.h) and mapped to exit codes by main().
#pragma once

#include <CLI/CLI.hpp>

namespace twinsim {

void AddRunCommand(CLI::App& app, int* exit_code);
void AddReplayCommand(CLI::App& app, int* exit_code);
void AddTrainCommand(CLI::App& app, int* exit_code);
void AddCompareCommand(CLI::App& app, int* exit_code);
void AddRegressCommand(CLI::App& app, int* exit_code);
void AddTunePidCommand(CLI::App& app, int* exit_code);
void AddExciteCommand(CLI::App& app, int* exit_code);

}  // namespace twinsim
