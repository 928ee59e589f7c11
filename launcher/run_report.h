#pragma once
/// The run report: what `rig run` prints and writes as JSON, as plain data, built once at the
/// end of a run by either executor and written by two writers that know nothing of processes
/// or transport.

#include <iosfwd>
#include <map>
#include <string>
#include <vector>

#include "core/rig_values.h"

#include "launcher/run_monitor.h"
#include "launcher/run_plan.h"
#include "launcher/verdict.h"

namespace nimble::launcher {

/// How one process of the run ended.
struct ProcessOutcome {
  std::string name;
  long long pid = -1;
  bool exited = false;
  int exit_code = -1;
  int signal = 0;
  std::string ended;       ///< "exited with code 0", "was killed by signal 9 (Killed)", "running"
  int64_t heartbeats = 0;  ///< heartbeats the launcher heard from it
  /// A Python participant in the process's place (scenario section `participants`): "Python
  /// MyController of my_controller.py"; "" for the rig's own process.
  std::string python;
};

/// What a run's log holds: whole events only, also when a write failed.
struct LogKept {
  std::string file;
  int64_t events = 0;  ///< whole events in the file
  int64_t bytes = 0;
  double sim_time_s = 0;  ///< the simulated time of its last event
  std::string failure;    ///< "" or why recording stopped ("log write failed at byte N of F: reason")
};

/// One host of the run and what ran on it.
struct HostSummary {
  std::string name;       ///< as in the scenario's hosts section
  bool launcher = false;  ///< the host that recorded and watched the run
  std::vector<std::string> processes;
  std::string address;            ///< its end of the emulated link ("" on one host)
  std::string network_namespace;  ///< the kernel's name of its namespace, e.g. "net:[4026532417]" ("" if unknown)
};

struct RunReport {
  std::string scenario;
  std::string clock;
  unsigned long long seed = 0;
  std::string transport;         ///< the LCM URL, or "in process"
  std::string transport_detail;  ///< network namespace etc. (may be empty)
  std::string log_file;
  LogKept log;  ///< what the log holds (events 0 and no file: no log was written)
  /// The run's configuration digest (scenario_digest(): the resolved scenario and the content of
  /// every file it names); every process flew with it.
  std::string config_digest;
  double sim_time_s = 0.0;
  double wall_time_s = 0.0;
  std::map<std::string, ChannelSummary> channels;
  std::map<std::string, TimingSummary> timing;
  FlightSummary flight;
  EstimatorSummary estimator;  ///< samples == 0: no estimator in the run
  TrackingSummary tracking;    ///< samples == 0: no controller in the run
  std::map<std::string, nimble::CanHealth> can_health;
  std::vector<FaultRecord> faults;
  std::vector<ProcessOutcome> processes;
  std::vector<HostSummary> hosts;  ///< where the processes ran (empty: no hosts section)
  std::vector<TapFigures> taps;    ///< figures of the run's followers (RunOptions::tap), e.g. the live view
  Verdict verdict;

  double speed_x_realtime() const { return wall_time_s > 0 ? sim_time_s / wall_time_s : 0.0; }
};

/// Fills the parts of a report that come from the monitor (channels, timing, flight,
/// estimator, roll tracking, CAN health, faults) for a run of `sim_s` simulated and `wall_s`
/// wall seconds.
void fill_from_monitor(RunReport& report, const RunMonitor& monitor, double sim_s, double wall_s);

/// Each of report.processes' heartbeats heard (from `monitor`) and, for a process the scenario
/// replaces by a Python participant, which ("Python MyController of my_controller.py").
void describe_processes(RunReport& report, const Scenario& scenario, const RunMonitor& monitor);

/// The human-readable summary.
void write_report_text(std::ostream& out, const RunReport& report);
/// The summary as one JSON object (`rig run --json`).
std::string report_json(const RunReport& report);

/// Prints the summary (options.print_summary) and writes the JSON (options.json_file);
/// returns the verdict's exit code.
int finish_report(const RunReport& report, const RunOptions& options);

}  // namespace nimble::launcher
