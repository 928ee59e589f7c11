#pragma once
/// The run plan: everything `rig run` needs to know before it starts anything, loaded and
/// validated once from the scenario and the command line. Both executors (separate processes
/// over LCM, and in process) fly a RunPlan.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "contract/rates.h"
#include "core/param_table.h"
#include "launcher/hosts.h"
#include "scenario/scenario.h"

namespace nimble::launcher {

/// Exit codes of `rig run`.
constexpr int kRunOk = 0;
constexpr int kRunNotControlled = 1;  ///< the run completed but the vehicle was not controlled
constexpr int kRunBadInput = 2;       ///< bad scenario, flag or environment
constexpr int kRunFailed = 3;         ///< a process failed, did not start, or the run stalled
constexpr int kRunTimingDegraded = 4; ///< with --strict-timing: controlled, but real time was degraded
constexpr int kRunFailsafe = 5;       ///< the run completed with the controller in its failsafe
constexpr int kRunInterrupted = 130;  ///< stopped by SIGINT/SIGTERM

/// The clocks a scenario can be flown on (`clock:` or `--clock`).
/// realtime and lockstep run each process as its own OS process over LCM; inprocess flies
/// the same processes' code in one process and one thread, with lockstep semantics.
constexpr const char* kClockRealtime = "realtime";
constexpr const char* kClockLockstep = "lockstep";
constexpr const char* kClockInprocess = "inprocess";

/// The LCM URL of a run in its private network namespace (run.lcm_url: auto). The receive
/// buffer holds a burst of several hundred milliseconds of the rig's traffic.
constexpr const char* kNamespaceLcmUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608";

struct RunOptions {
  std::string scenario_file;
  std::vector<Override> overrides;   ///< --set key=value
  std::optional<std::string> clock;  ///< --clock realtime|lockstep|inprocess
  std::optional<uint64_t> seed;      ///< --seed N
  std::string log_file;              ///< --log FILE (default: rig_logs/<name>-<time>.lcmlog)
  std::string json_file;             ///< --json FILE
  std::string bin_dir;               ///< where nimble_plant etc. live (default: next to rig)
  bool progress = true;              ///< progress line on stderr
  bool print_summary = true;         ///< the run summary on stdout
  bool strict_timing = false;        ///< --strict-timing: a degraded real-time run exits kRunTimingDegraded
};

/// Settings of the launcher itself (scenario section `run`).
struct LaunchConfig {
  double ready_timeout_s = 15.0;   ///< every process must report READY within this [s]
  double stop_grace_s = 2.0;       ///< after RUN_CONTROL stop, before SIGTERM [s]
  double stall_timeout_s = 10.0;   ///< lockstep: no simulated progress for this long is a failure [s]
  double start_delay_s = 0.05;     ///< real time: t0 lies this far after the start command [s]
  /// A running process that sends no heartbeat for this long (wall clock) is lost
  /// (CODE_HEARTBEAT_LOST) and the run fails [s]. Heartbeats come at 2 Hz while running, so
  /// 2 s is four missed in a row.
  double heartbeat_timeout_s = 2.0;
  /// Processes of `processes` that the launcher does not start: they are started by hand (on
  /// another machine of the lab, docs/machines.md "Running across machines") with the run's resolved
  /// scenario and LCM URL, which the launcher prints; it waits for their READY as for the others.
  std::vector<std::string> external_processes;
  std::string lcm_url = "auto";    ///< "auto": private namespace (or host multicast) per run
  std::string network_namespace = "auto";  ///< auto | always | never
  std::vector<int> rig_cpus;       ///< CPUs for the rig's processes (empty: no pinning)
  std::vector<int> launcher_cpus;  ///< CPUs for the launcher itself (empty: no pinning)
};

/// Judgement of the flight (scenario section `summary`).
struct JudgeConfig {
  double max_phi_deg = 80.0;        ///< beyond this roll the vehicle is not controlled
  double max_theta_deg = 60.0;      ///< beyond this pitch (the pitch set-point limit) neither
  double hover_phi_deg = 5.0;       ///< final |phi| for "returned to hover"
  double hover_p_radps = 0.5;       ///< final |p| for "returned to hover"
  double hover_v_mps = 0.3;         ///< final |v| for "returned to hover"
  /// Real time: a run in which some process received more than this fraction of a stream
  /// channel's messages late (run.late_threshold_us), or overran more than max_overrun_fraction
  /// of its cycles, is "real-time degraded". 1 % each: a lab loop that misses one cycle in a
  /// hundred no longer replays the paper's manoeuvres at their timing.
  double max_late_fraction = 0.01;
  double max_overrun_fraction = 0.01;
};

/// The `run` section's numeric parameters (defaults: LaunchConfig's); lcm_url,
/// network_namespace, the CPU lists and the processes' own keys are read on their own.
const ParamTable<LaunchConfig>& launch_params();
/// The `summary` section's parameters (defaults: JudgeConfig's).
const ParamTable<JudgeConfig>& judge_params();

struct RunPlan {
  Scenario scenario;            ///< resolved: bases merged, --clock/--seed/--set applied, validated
  LaunchConfig launch;
  JudgeConfig judge;
  contract::ProcessRates rates;
  double logger_period_ms = 10.0;  ///< lockstep.logger_period_ms
  HostPlacement hosts;             ///< the `hosts` section: where each process runs (hosts.h)
  bool inprocess() const { return scenario.clock == kClockInprocess; }
  bool lockstep() const { return scenario.clock != kClockRealtime; }  ///< lockstep semantics
};

/// Loads and validates a scenario with the run options applied (every process section,
/// the models and the manoeuvre) without starting anything.
/// @throws ConfigError naming the file, key and value.
RunPlan load_run_plan(const RunOptions& options);

/// The log file of a run: `options.log_file`, or rig_logs/<name>-<time>.lcmlog.
std::string log_file_for(const RunPlan& plan, const RunOptions& options);

/// Over the CAN link with a candump log and no file named: names <log>.candump (absolute) in
/// the plan's scenario, so that the frames are recorded next to the run's LCM log.
void place_candump_log(RunPlan& plan, const std::string& log_file);

/// Writes the resolved scenario next to the log (`<log>.scenario.yaml`); returns its path.
/// @throws std::runtime_error if it cannot be written.
std::string write_resolved_scenario(const RunPlan& plan, const std::string& log_file);

}  // namespace nimble::launcher
