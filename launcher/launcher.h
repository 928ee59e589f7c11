#pragma once
/// The launcher behind `rig run`: starts the processes of a scenario, each as its own OS
/// process, over a run-private LCM URL; waits until every one reports ready; starts the
/// run in real time or lockstep; records every channel to an LCM log; stops the processes
/// cleanly (RUN_CONTROL stop, grace period, SIGTERM, SIGKILL); prints the run summary.
///
/// Subscribes to every channel (".*") for the log and the summary; publishes RUN_CONTROL.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "scenario/scenario.h"

namespace nimble::launcher {

/// Exit codes of `rig run`.
constexpr int kRunOk = 0;
constexpr int kRunNotControlled = 1;  ///< the run completed but the vehicle was not controlled
constexpr int kRunBadInput = 2;       ///< bad scenario, flag or environment
constexpr int kRunFailed = 3;         ///< a process failed, did not start, or the run stalled
constexpr int kRunInterrupted = 130;  ///< stopped by SIGINT/SIGTERM

struct RunOptions {
  std::string scenario_file;
  std::vector<Override> overrides;   ///< --set key=value
  std::optional<std::string> clock;  ///< --clock realtime|lockstep
  std::optional<uint64_t> seed;      ///< --seed N
  std::string log_file;              ///< --log FILE (default: rig_logs/<name>-<time>.lcmlog)
  std::string json_file;             ///< --json FILE
  std::string bin_dir;               ///< where nimble_plant etc. live (default: next to rig)
  bool progress = true;              ///< progress line on stderr
};

/// Loads and validates a scenario with the run options applied (every process section,
/// the models and the manoeuvre) without starting anything.
/// @throws ConfigError naming the file, key and value.
Scenario prepare_scenario(const RunOptions& options);

/// Runs a scenario; returns one of the kRun* exit codes. Prints the summary on stdout and
/// errors on stderr. Must be called before the process has started any thread.
int run_scenario(const RunOptions& options);

/// `rig check`: whether this host can run LCM multicast, with the fix if not. Returns 0 if
/// runs can proceed (directly or in a private namespace), 1 otherwise.
int check_host();

}  // namespace nimble::launcher
