#pragma once
/// Sub-commands of the `rig` command-line tool, one file each (cli/<name>_command.cc). Each takes
/// the arguments after its name and returns the process exit code: 0 success, 1 the command ran
/// but its check failed, 2 bad usage or bad input (message on stderr). Their one-line usage is
/// written once, in cli/rig_main.cc's command table (`rig --help`); each command's options in its
/// own file (`rig <command> --help`).

#include <string>
#include <vector>

#include "cmdline/args.h"  // cmdline::kExitUsage

namespace nimble::cli {

/// cli/model_command.cc.
int run_model_command(const std::vector<std::string>& args);
/// cli/run_command.cc.
int run_run_command(const std::vector<std::string>& args);
/// cli/view_command.cc.
int run_view_command(const std::vector<std::string>& args);
/// cli/sweep_command.cc.
int run_sweep_command(const std::vector<std::string>& args);
/// cli/params_command.cc.
int run_params_command(const std::vector<std::string>& args);
/// cli/check_command.cc.
int run_check_command(const std::vector<std::string>& args);
/// cli/spy_command.cc.
int run_spy_command(const std::vector<std::string>& args);
/// cli/identify_command.cc.
int run_identify_command(const std::vector<std::string>& args);
/// cli/discrepancy_command.cc.
int run_discrepancy_command(const std::vector<std::string>& args);
/// cli/power_command.cc. run_discrepancy_command hands it every command line with --power
int run_discrepancy_power_command(const std::vector<std::string>& args);
/// cli/validate_command.cc.
int run_validate_command(const std::vector<std::string>& args);
/// cli/export_command.cc.
int run_export_command(const std::vector<std::string>& args);
/// cli/turbulence_command.cc.
int run_turbulence_command(const std::vector<std::string>& args);
/// cli/turbulence_response_command.cc.
int run_turbulence_response_command(const std::vector<std::string>& args);
/// cli/reproduce_command.cc.
int run_reproduce_command(const std::vector<std::string>& args);
/// cli/loop_command.cc.
int run_loop_command(const std::vector<std::string>& args);

}  // namespace nimble::cli
