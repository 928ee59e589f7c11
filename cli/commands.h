#pragma once
/// Sub-commands of the `rig` command-line tool. Each takes the arguments after
/// its name and returns the process exit code: 0 success, 1 the command ran but
/// its check failed, 2 bad usage or bad input (message on stderr).

#include <string>
#include <vector>

namespace nimble::cli {

/// Exit code for bad usage or bad input.
constexpr int kExitUsage = 2;

/// `rig model <model.yaml> [--vehicle <vehicle.yaml>] [--json]`
int run_model_command(const std::vector<std::string>& args);

}  // namespace nimble::cli
