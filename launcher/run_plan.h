#pragma once
/// The run plan: everything `rig run` needs to know before it starts anything, loaded and
/// validated once from the scenario and the command line. Both executors (separate processes
/// over LCM, and in process) fly a RunPlan.

#include <cstdint>
#include <functional>
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
constexpr int kRunNotControlled = 1;   ///< the run completed but the vehicle was not controlled
constexpr int kRunBadInput = 2;        ///< bad scenario, flag or environment
constexpr int kRunFailed = 3;          ///< a process failed, did not start, or the run stalled
constexpr int kRunTimingDegraded = 4;  ///< with --strict-timing: controlled, but real time was degraded
constexpr int kRunFailsafe = 5;        ///< the run completed with the controller in its failsafe
/// The run completed within the control limits, but the roll did not follow the controller's
/// reference: the tracking error beyond its bounds, or a sustained or growing oscillation.
constexpr int kRunNotTracking = 6;
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

/// Figures of a RunTap for the run summary: a section `title` in the text, `key` in the JSON.
struct TapFigures {
  std::string key;                                        ///< JSON key, e.g. "live_view"
  std::string title;                                      ///< text label, e.g. "live view"
  std::vector<std::pair<std::string, long long>> values;  ///< name and figure, in order
  std::string note;  ///< one line after the figures (e.g. where it was served); may be empty
};

/// Someone besides the recorder who follows a run as it flies (rig run --foxglove: the live
/// view), in either executor. Every member may be empty.
struct RunTap {
  /// Called once when the launcher may start threads (after it moved into the run's network
  /// namespace, which needs it single-threaded), before any rig process starts.
  std::function<void()> start;
  /// Every message of the run, on the recording thread, as the recorder logs it. Must be quick
  /// and never block: it runs where the log is written (and, in lockstep, paces the run).
  std::function<void(const std::string& channel, const void* data, int size)> message;
  /// The run's state: "running" at its start (t_s 0), "done" with the verdict's text at its end
  /// (t_s: the simulated time reached).
  std::function<void(const std::string& state, const std::string& verdict, double t_s)> state;
  /// Its figures for the run summary, asked for once at the end.
  std::function<TapFigures()> figures;
};

struct RunOptions {
  std::string scenario_file;
  std::vector<Override> overrides;   ///< --set key=value
  std::optional<std::string> clock;  ///< --clock realtime|lockstep|inprocess
  std::optional<uint64_t> seed;      ///< --seed N
  std::string log_file;              ///< --log FILE (default: rig_logs/<name>-<time>.lcmlog)
  std::string json_file;             ///< --json FILE
  int64_t log_max_bytes = 0;         ///< --log-max-bytes N: the log may take at most N bytes (0: no limit)
  bool space_check = true;           ///< false (--no-space-check): fly even if the log's filesystem looks too small
  std::string bin_dir;               ///< where nimble_plant etc. live (default: next to rig)
  bool progress = true;              ///< progress line on stderr
  bool print_summary = true;         ///< the run summary on stdout
  /// A step after the log is closed and before the summary (rig run --mcap: the export), given
  /// the log's name: "" when it succeeded, else what failed, which turns the run's result into
  /// `failed: ...` (exit 3) so that the summary and the exit code agree.
  std::function<std::string(const std::string& log_file)> after_log;
  bool strict_timing = false;  ///< --strict-timing: a degraded real-time run exits kRunTimingDegraded
  RunTap tap;                  ///< a live follower of the run (rig run --foxglove); empty: none
};

/// Settings of the launcher itself (scenario section `run`).
struct LaunchConfig {
  double ready_timeout_s = 15.0;  ///< every process must report READY within this [s]
  double stop_grace_s = 2.0;      ///< after RUN_CONTROL stop, before SIGTERM [s]
  double stall_timeout_s = 10.0;  ///< lockstep: no simulated progress for this long is a failure [s]
  double start_delay_s = 0.05;    ///< real time: t0 lies this far after the start command [s]
  /// A running process that sends no heartbeat for this long (wall clock) is lost
  /// (CODE_HEARTBEAT_LOST) and the run fails [s]. Heartbeats come at 2 Hz while running, so
  /// 2 s is four missed in a row.
  double heartbeat_timeout_s = 2.0;
  /// Processes of `processes` that the launcher does not start: they are started by hand (on
  /// another machine of the lab, docs/machines.md "Running across machines") with the run's resolved
  /// scenario and LCM URL, which the launcher prints; it waits for their READY as for the others.
  std::vector<std::string> external_processes;
  /// The interpreter of the scenario's Python participants (section `participants`), started as
  /// `python -m nimble_rig.node`: Debian's, which has the python3-numpy the module needs.
  std::string python = "/usr/bin/python3";
  std::string lcm_url = "auto";            ///< "auto": private namespace (or host multicast) per run
  std::string network_namespace = "auto";  ///< auto | always | never
  std::vector<int> rig_cpus;               ///< CPUs for the rig's processes in real time (empty: no pinning)
  /// CPUs for the rig's processes in lockstep (empty: no pinning). Lockstep has no deadlines:
  /// the participants a tick wakes step side by side on every CPU, not in turn on one.
  std::vector<int> lockstep_cpus;
  const std::vector<int>& rig_cpus_for(bool lockstep) const { return lockstep ? lockstep_cpus : rig_cpus; }
  std::vector<int> launcher_cpus;  ///< CPUs for the launcher itself (empty: no pinning)
};

/// Judgement of the flight (scenario section `summary`).
struct JudgeConfig {
  double max_phi_deg = 80.0;    ///< beyond this roll the vehicle is not controlled
  double max_theta_deg = 60.0;  ///< beyond this pitch (the pitch set-point limit) neither
  double hover_phi_deg = 5.0;   ///< final |phi| for "returned to hover"
  double hover_p_radps = 0.5;   ///< final |p| for "returned to hover"
  double hover_v_mps = 0.3;     ///< final |v| for "returned to hover"
  /// Real time: a run in which some process received more than this fraction of a stream
  /// channel's messages late (run.late_threshold_us), or overran more than max_overrun_fraction
  /// of its cycles, is "real-time degraded". 1 % each: a lab loop that misses one cycle in a
  /// hundred no longer replays the paper's manoeuvres at their timing.
  double max_late_fraction = 0.01;
  double max_overrun_fraction = 0.01;
  /// The JSON report's `trace`: p, v and phi of TRUTH at this rate of rig time [Hz]; 0: none.
  /// `rig sweep --report` sets it for the envelopes across seeds.
  double trace_hz = 0.0;
  /// Roll tracking: the true roll against the controller's roll reference (verdict.h
  /// judge_tracking). The defaults come from flights in process, seeds 1-8. Nominal: every
  /// scenario of rig_configs/, the identification train on the models of sets 1-5, on the truth
  /// and without the pilot, the fault flights that fly on (docs/faults.md, on hover and on the
  /// train). Within the loop's margins, as the tests fly them: hover and the 6 Hz doublet at 0.7x
  /// the delay and gain margins of rig loop (fast and slow gains), the slow gains' trains with
  /// 5-15 ms of actuator delay (the pilot and the lateral inflow off, as the discrepancy tests
  /// fly them) and at 0.7x their delay margin, the fast gains' manoeuvres at 0.7x theirs.
  /// Beyond the margins: the same at 1.3x, hover with 10-14.3 ms of actuator delay (20 s), the
  /// identification train with 10-30 ms.
  /// The error's size says how hard the manoeuvre is as much as how well the loop follows it
  /// (the slow gains lag their doublets by tens of degrees): these two bounds are coarse, a
  /// loop that lost its margin is named by its oscillation (below).
  /// RMS over the run: nominal at most 10.7 deg (yaw_hold_lateral4; cl_doublet_train_slow
  /// 10.5), within the margins 14.7 deg (cl_doublet_train_slow with 15 ms of delay, at the roll
  /// limit); the identification train with 30 ms of delay 39 deg (hover with 14.3 ms: 17.7 deg,
  /// named by its oscillation). 1.35x above the worst within the margins, half the train's.
  double max_tracking_rms_deg = 20.0;
  /// Largest |error|: nominal at most 56.1 deg (cl_doublet_train_slow), within the margins
  /// 76 deg (the same with 15 ms of delay); the oscillations beyond the margins peak at 8-85 deg.
  /// 1.2x above the worst within the margins: the roll a quarter turn off its reference.
  double max_tracking_error_deg = 90.0;
  /// Oscillation (verdict.h find_oscillation): oscillation_cycles cycles in a row of the tracking
  /// error, each half-cycle's peak at least oscillation_amplitude_deg, the roll reference still
  /// in each, every full period within oscillation_period_tolerance of their mean, the amplitude
  /// decaying with a damping ratio below oscillation_max_damping.
  /// Largest such cycles: none in the nominal flights, 2.6 deg within the margins (the 6 Hz
  /// doublet at 0.7x the delay margin, in its last seconds); beyond the margins at least 7.0 deg
  /// (the slow gains' limit cycle at 1.3x the gain margin), 28 deg in hover with 14.3 ms of
  /// delay, 55 deg in the train with 30 ms. 1.5x above the first, 1.75x below the smallest limit
  /// cycle.
  double oscillation_amplitude_deg = 4.0;
  /// Three cycles: longer than a doublet's forced response; every oscillation beyond the margins
  /// above has them (the train's with 30 ms of delay from about 3 s of its 6 s).
  int oscillation_cycles = 3;
  /// Full periods within 7 % of their mean in the oscillations beyond the margins, 5 % in the
  /// ringing within them; 0.2 leaves room for a limit cycle that drifts.
  double oscillation_period_tolerance = 0.2;
  /// Damping ratio of the free ringing (cycles of at least oscillation_amplitude_deg): nominal
  /// at least 0.063 (the fast gains' dominant pair, 0.069 by rig loop); within the margins
  /// 0.0057 (the 30 deg nonlinear doublet at 0.7x the delay margin; the 6 Hz doublet there
  /// 0.009); beyond them at most 0.0010 (the identification train's limit cycle with 30 ms of
  /// delay, settling from above), below 0 where the oscillation grows. Between the two, 2.3x
  /// below the first and 2.5x above the second: an amplitude that loses less than 1.6 % a cycle
  /// is sustained.
  double oscillation_max_damping = 0.0025;
  /// A half-cycle in which the reference moved belongs to the manoeuvre: counted, the
  /// identification train's second doublet, which re-excites the ringing of the first, looks
  /// like an oscillation that does not decay, of up to 9.4 deg nominally and 16 deg within the
  /// margins. Half the tracking dead band (TrackingRecorder::kDeadBandDeg); any value from 0.1
  /// to 2 deg gives the figures above.
  double oscillation_reference_still_deg = 0.5;
};

/// The `run` section's numeric parameters (defaults: LaunchConfig's); lcm_url,
/// network_namespace, the CPU lists and the processes' own keys are read on their own.
const ParamTable<LaunchConfig>& launch_params();
/// The `summary` section's parameters (defaults: JudgeConfig's).
const ParamTable<JudgeConfig>& judge_params();

struct RunPlan {
  Scenario scenario;  ///< resolved: bases merged, --clock/--seed/--set applied, validated
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
