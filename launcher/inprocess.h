#pragma once
/// The in-process executor: `rig run <scenario> --clock inprocess`.
///
/// Flies a run plan with every process of the scenario (plant, controller, mocap, estimator,
/// both sides of the CAN bridge) built from the same node classes the rig's executables run,
/// in this process and on one thread, without transport: their Buses share an InprocessHub,
/// the plant is the lockstep master, the others are participants fed its RIG_CLOCK ticks, so
/// each consumer uses what was published at earlier ticks, as in `--clock lockstep`. The TRUTH
/// messages are byte for byte those of a lockstep run of the same scenario and seed. The CAN
/// link, when the scenario has one, carries real frames through the rig's codec over an
/// InprocessCanBus. Every message goes to the same recorder and monitor as in the other
/// executors: the log has every channel, the report and verdict are the same.

#include <functional>
#include <map>
#include <memory>
#include <string>

#include "launcher/run_plan.h"
#include "launcher/run_report.h"

namespace nimble::transport {
class ProcessNode;
struct NodeOptions;
}  // namespace nimble::transport

namespace nimble::launcher {

/// A participant of one's own flying in place of one of the scenario's processes (a controller
/// written in Python: nimble_rig.fly(participants=)): built on the run's hub with that process's
/// node options (its name, the scenario), joined and stepped by the lockstep master like the
/// rig's own, its heartbeat, health and faults on the bus as theirs are.
struct CustomParticipant {
  transport::ProcessNode* node = nullptr;  ///< its process frame: bus, tasks, heartbeat
  std::shared_ptr<void> owner;             ///< keeps it alive until the run's end
};
/// Builds a custom participant. Something it throws ends the run before it starts; something its
/// tasks throw ends the run as a rig process's failure does, naming the process.
using ParticipantFactory = std::function<CustomParticipant(const transport::NodeOptions& options)>;

struct InprocessOptions {
  std::string log_file;       ///< the LCM log; empty: none (the monitor still sees every message)
  int64_t log_max_bytes = 0;  ///< the log's limit (0: none): reaching it ends the run, as a full disk does
  bool progress = false;      ///< progress line on stderr
  /// Compute the report's configuration digest (scenario_digest(): the tree and every file it
  /// names, read again); false leaves it empty, for a caller that keeps only the verdict of
  /// many flights of one plan.
  bool config_digest = true;
  /// Every message of the run, in the order the log has them (on the recording thread, after
  /// the recorder and the monitor); empty: none. Something it throws ends the run: it is
  /// rethrown by fly_inprocess().
  std::function<void(const std::string& channel, const void* data, int size)> on_message;
  /// Participants of one's own, by the name of the scenario's process each replaces (not the
  /// plant: it is the lockstep master). A name the scenario does not run is a ConfigError.
  std::map<std::string, ParticipantFactory> replace;
};

/// Flies `plan` (any clock: it is flown in process) and returns its report; prints nothing
/// but the progress line. A failure during the run (a process that throws, a participant
/// that does not acknowledge) ends the run and is in the verdict.
/// @throws ConfigError for a bad configuration found while the processes are built;
///         std::runtime_error if the log cannot be written.
RunReport fly_inprocess(const RunPlan& plan, const InprocessOptions& options);

/// `rig run --clock inprocess`: writes the resolved scenario next to the log, flies the plan,
/// prints the summary, writes the JSON; returns the verdict's exit code.
int run_inprocess(const RunPlan& plan, const RunOptions& options);

}  // namespace nimble::launcher
