#pragma once
/// What every rig process shares before its node runs: the exit codes, the command line
/// (`--scenario FILE [--name N] [--lcm-url URL]`), and the real-time scheduling policy the
/// executable takes (process_main(), transport/process_main.h).

#include <cstdint>
#include <optional>
#include <string>

#include "transport/inprocess_hub.h"

namespace nimble::transport {

/// Exit codes of rig processes.
constexpr int kExitOk = 0;
constexpr int kExitConfig = 2;      ///< bad configuration or command line
constexpr int kExitAckTimeout = 3;  ///< lockstep participant did not acknowledge in time
constexpr int kExitFault = 4;       ///< other fatal fault at run time

/// Command-line options common to every rig process.
struct NodeOptions {
  std::string name;             ///< process name, used on HEARTBEAT, FAULT, STEP_ACK
  std::string scenario_file;    ///< resolved scenario YAML written by the launcher
  std::string lcm_url;          ///< LCM URL of the run
  InprocessHub* hub = nullptr;  ///< set: the node is one of a run flown in one process (no LCM)
};

/// How a process's node runs in real time (scenario section `run`). Ignored in lockstep and in
/// process. The process's SCHED_FIFO priority is the executable's business (process_main()).
struct RealtimeSettings {
  int64_t spin_ns = 0;            ///< wake this long before each deadline and spin to it
  int64_t late_threshold_ns = 0;  ///< a received stream message later than this is late (0: not counted)
  bool channel_filter = false;    ///< drop unsubscribed channels in the kernel (Bus::enable_channel_filter)
  /// Over LCM: give up waiting for RUN_CONTROL start after this long (0: wait until stopped).
  int64_t start_wait_ns = 0;
};

/// Puts the calling process under SCHED_FIFO at `priority` (1..99) with its memory locked,
/// before it starts any thread (LCM's receive thread inherits the policy). 0 does nothing.
/// Returns an empty string on success, otherwise why it failed (the caller reports it).
std::string apply_realtime_priority(int priority);

/// Records why this process could not take run.realtime_priority (process_main() sets it; the
/// scheduling policy belongs to the process, not to a node). Every ProcessNode over LCM reports
/// it as a CODE_REALTIME_UNAVAILABLE warning.
void set_realtime_problem(const std::string& why);
const std::string& realtime_problem();

/// Parses the command line of rig process `program` (the executable's name, used in its help and
/// messages): `--scenario FILE [--name N] [--lcm-url URL]`, `default_name` being --name's default.
/// Returns the exit code if the process ends here: 0 after --help (printed on stdout), kExitConfig
/// after a usage error (on stderr: "<program>: <what>", the usage line and a pointer to --help).
/// Otherwise fills `options` and returns std::nullopt.
std::optional<int> parse_node_options(int argc, char** argv, const std::string& program,
                                      const std::string& default_name, NodeOptions& options);

}  // namespace nimble::transport
