#pragma once
/// The `main()` every rig process shares: parse the common flags, load the resolved
/// scenario, install the stop signals, build the node and run it. --help prints the help on
/// stdout (exit 0); errors before the run (bad flags or configuration) go to stderr with exit
/// code kExitConfig.

#include <exception>
#include <functional>
#include <iostream>
#include <memory>
#include <string>

#include "core/config.h"
#include "scenario/scenario.h"
#include "transport/node.h"

namespace nimble::transport {

/// The real-time settings of the scenario's `run` section, as every rig process's node applies them.
inline RealtimeSettings realtime_settings(const Scenario& scenario) {
  const ProcessRunOptions run = process_run_options(scenario);
  RealtimeSettings r;
  r.spin_ns = static_cast<int64_t>(run.spin_us) * 1000;
  r.late_threshold_ns = run.late_threshold_us * 1000;
  r.channel_filter = run.channel_filter != 0;
  r.start_wait_ns = static_cast<int64_t>(run.start_wait_s * 1e9);
  return r;
}

/// The node of a rig process: the scenario's real-time settings, its digest on every heartbeat,
/// and its faults applied to what the process publishes.
inline std::unique_ptr<ProcessNode> make_process_node(const Scenario& scenario, const NodeOptions& options) {
  auto node = std::make_unique<ProcessNode>(options, realtime_settings(scenario), scenario_digest(scenario));
  node->inject_faults(scenario.faults, scenario.seed);
  return node;
}

/// Runs a rig process: parses the common flags, loads the resolved scenario, raises the
/// priority in real time, installs the stop signals, then `run(scenario, options)` builds the
/// node and runs it, returning its exit code. `program` names the executable in messages;
/// `default_name` is the process name used when --name is not given.
inline int run_process_main(int argc, char** argv, const char* program, const char* default_name,
                            const std::function<int(const Scenario&, const NodeOptions&)>& run) {
  try {
    NodeOptions options;
    if (const auto done = parse_node_options(argc, argv, program, default_name, options)) return *done;
    const Scenario scenario = load_scenario(options.scenario_file);
    // SCHED_FIFO before the node starts LCM's receive thread, which inherits it; in real time
    // only: a lockstep run has no deadlines and runs as fast as it can, and under SCHED_FIFO it
    // would take its CPU from everything else on the machine.
    if (scenario.clock == "realtime") {
      set_realtime_problem(apply_realtime_priority(process_run_options(scenario).realtime_priority));
    }
    ProcessNode::install_signal_handlers();
    return run(scenario, options);
  } catch (const ConfigError& e) {
    std::cerr << program << ": config error: " << e.what() << "\n";
    return kExitConfig;
  } catch (const std::exception& e) {
    std::cerr << program << ": error: " << e.what() << "\n";
    return kExitConfig;
  }
}

/// Runs process `Node` (constructible from (const Scenario&, const NodeOptions&), with
/// `int run()`): run_process_main() with that node.
template <typename Node>
int process_main(int argc, char** argv, const char* program, const char* default_name) {
  return run_process_main(argc, argv, program, default_name, [](const Scenario& scenario, const NodeOptions& options) {
    Node node(scenario, options);
    return node.run();
  });
}

}  // namespace nimble::transport
