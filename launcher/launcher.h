#pragma once
/// `rig run` and `rig check`.
///
/// run_scenario() loads the run plan (run_plan.h) and flies it on one of two executors:
///  - realtime and lockstep (this file's launcher): each rig process is its own OS process
///    over a run-private LCM URL; the launcher waits until every one reports ready, starts
///    the run, records every channel (recorder.h), stops the processes cleanly (RUN_CONTROL
///    stop, grace period, SIGTERM, SIGKILL); in lockstep its recorder is a participant, so the
///    run never outpaces the log.
///  - inprocess (inprocess.h): the same processes' code in this process, without transport.
/// Either way the run ends with the same report (run_report.h) and verdict (verdict.h).
///
/// Subscribes to every channel (".*") for the log and the summary; publishes RUN_CONTROL.

#include "launcher/run_plan.h"

namespace nimble::launcher {

/// Runs a scenario; returns one of the kRun* exit codes. Prints the summary on stdout and
/// errors on stderr. Must be called before the process has started any thread.
int run_scenario(const RunOptions& options);

/// "" if `file` can be written (opened for appending; a file made by the check is removed
/// again), else why not: outputs are checked before anything flies.
std::string writable_problem(const std::string& file);

/// `rig check`: whether this host can run LCM multicast, with the fix if not. Returns 0 if
/// runs can proceed (directly or in a private namespace), 1 otherwise. `json_target` (a file,
/// or "-" for stdout with the text on stderr) also gets the findings as JSON.
int check_host(const std::string& json_target = "");

}  // namespace nimble::launcher
