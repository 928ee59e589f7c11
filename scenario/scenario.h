#pragma once
/// Rig scenarios: the YAML files in rig_configs/ that say what a run is.
///
/// A scenario names the models, the processes to launch, the run's duration and clock,
/// and one section per process. Loading resolves it into one self-contained tree:
///  1. every mapping with a `base: <file.yaml>` key is merged over the content of that
///     file (the mapping's own keys win; bases may nest);
///  2. relative paths (keys model, longitudinal_model, vehicle, manoeuvre, base, and each
///     participant's `python` file) become absolute, relative to the file they are written in;
///  3. `--set a.b.c=value` overrides from the command line replace single values; except
///     `--set a.b.base=FILE`, which is applied before step 1: the section stands on FILE
///     (relative to the working directory) instead of the base it names, its own keys still
///     winning (`--set sensing.base=rig_configs/sensing/nimble_flight_vibration.yaml`).
/// The launcher writes the resolved tree next to the run's log and hands it to every
/// process, so a run can always be repeated from its record.

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "core/config.h"
#include "core/input_file.h"
#include "contract/faults.h"
#include "core/param_table.h"

namespace nimble {

/// One `key.path=value` override from the command line.
struct Override {
  std::string key_path;
  std::string value;  ///< parsed as YAML (number, string, list or mapping)
};

/// Parses "a.b=1" into an Override. @throws ConfigError naming the text.
Override parse_override(const std::string& text);

/// Where a key of a resolved scenario was written: the file (the scenario or one of its base
/// files) and line, or "--set" (line -1) for a command-line override.
struct KeyOrigin {
  std::string file;
  int line = -1;
};
/// Origin of every key path of a resolved scenario ("plant.rate_hz" -> file and line).
using KeyOrigins = std::map<std::string, KeyOrigin>;

/// Loads a scenario file, merges bases, absolutises paths and applies overrides. `origins`
/// (if given) receives where each key came from (merging loses yaml-cpp's line marks).
/// @throws ConfigError naming the file and key.
YAML::Node load_scenario_tree(const std::string& file, const std::vector<Override>& overrides = {},
                              KeyOrigins* origins = nullptr);

/// `error` (about a key of the scenario `scenario_file`) pointed at where its key was written:
/// the base file and line, or --set for a command-line value. Errors about other files, or
/// keys without a recorded origin, come back unchanged.
ConfigError locate_error(const ConfigError& error, const std::string& scenario_file, const KeyOrigins& origins);

/// A participant of one's own in place of one of the scenario's processes, written in Python
/// (section `participants`: `controller: {python: my_controller.py, class: MyController}`). The
/// launcher starts it as its own process (`python3 -m nimble_rig.node`) in lockstep and real time;
/// nimble_rig.fly() flies it in process. python/nimble_rig/participant.py says what the class is.
struct ParticipantSpec {
  std::string python_file;  ///< the Python file that defines the class (absolute once resolved)
  std::string class_name;   ///< a top-level class of that file
  YAML::Node arguments;     ///< keyword arguments of the class's constructor (a mapping; null: none)
};

/// The processes a participant of one's own may replace: not the plant (the lockstep master, and
/// the vehicle itself), nor the sides of the CAN bridge (they speak SocketCAN, not LCM).
const std::vector<std::string>& replaceable_processes();

/// The top-level facts of a resolved scenario; process sections stay in `root` and are
/// validated by their owners (plant_config_from, controller config, ...).
struct Scenario {
  std::string file;  ///< the file it was loaded from (or the resolved copy)
  std::string name;
  std::string description;
  double duration_s = 0.0;
  std::string clock;  ///< "realtime", "lockstep" or "inprocess" (launcher/run_plan.h)
  uint64_t seed = 1;
  std::string model_file;               ///< lateral derivative model
  std::string longitudinal_model_file;  ///< optional
  std::string vehicle_file;             ///< optional override of the model's vehicle
  /// Process names to launch, e.g. plant, controller. With actuator_link "can" the two
  /// sides of the CAN bridge (can_flight, can_rig) are added if not listed.
  std::vector<std::string> processes;
  /// How actuator commands and feedback travel between controller and plant: "lcm"
  /// (directly) or "can" (through nimble_can_bridge and SocketCAN; section can_bridge).
  std::string actuator_link = "lcm";
  /// Faults injected into the run (section `faults`, scenario/fault_section.h); empty: none.
  std::vector<contract::FaultSpec> faults;
  /// Participants written in Python, by the process each replaces (section `participants`).
  std::map<std::string, ParticipantSpec> participants;
  /// The rate each stream channel of the run is expected at [Hz] (contract::expected_rates() of
  /// the configured process rates). The launcher derives it when it plans the run and writes it
  /// into the resolved scenario (key `expected_rates_hz`) that the processes load, so that each
  /// process judges its inputs by the run's rates; a value in a scenario file is replaced there.
  /// Empty for a scenario no launcher resolved: nothing is expected.
  std::map<std::string, double> expected_rates_hz;
  YAML::Node root;
  KeyOrigins origins;  ///< where each key was written (locate_error)

  /// The section of one process (an empty mapping if absent) as a strict ConfigMap.
  ConfigMap section(const std::string& name) const;
  bool has_section(const std::string& name) const { return static_cast<bool>(root[name]); }
  /// True if `process` is one of the run's processes.
  bool runs(const std::string& process) const;
  /// expected_rates_hz of `channel`; 0 (nothing expected) if the run does not carry it.
  double expected_rate(const std::string& channel) const;
};

/// Sets the run's expected stream rates (Scenario::expected_rates_hz) and writes them into the
/// scenario's tree, so that the resolved scenario the processes load carries them.
void set_expected_rates(Scenario& scenario, const std::map<std::string, double>& rates_hz);

/// The channel on which the plant takes its actuator commands: ACTUATOR_CMD over the LCM
/// link, ACTUATOR_CMD_CAN (published by the rig side of the bridge) over the CAN link.
std::string plant_command_channel(const Scenario& scenario);

/// Known top-level keys that are sections owned by processes or by the launcher.
const std::vector<std::string>& scenario_section_keys();

/// Validates the top level of a resolved tree. @throws ConfigError naming the key.
Scenario scenario_from_tree(const YAML::Node& root, const std::string& file);

/// The scenario's manoeuvre file (absolute: load_scenario resolves the path), or "" when it names
/// none. `required`: a scenario without one is an error saying `why` it needs one.
/// @throws ConfigError naming `manoeuvre` if it is not a file name (a scalar), or missing when required.
std::string manoeuvre_file(const Scenario& scenario, bool required = false, const std::string& why = "");

/// load_scenario_tree + scenario_from_tree.
Scenario load_scenario(const std::string& file, const std::vector<Override>& overrides = {});

/// Options of the `run` section that the processes themselves apply (the launcher
/// validates the whole section).
struct ProcessRunOptions {
  /// Real time: SCHED_FIFO priority of the rig processes, 1..99; 0 = default scheduler.
  /// 50, the middle of SCHED_FIFO's 1..99: above every ordinary process. Where it cannot be
  /// applied (no root, no CAP_SYS_NICE) the process runs on with a warning the summary shows.
  int realtime_priority = 50;
  /// Real time: "timer" (the controller runs on its own 512 Hz deadlines) or "state"
  /// (each cycle starts when the state it needs arrives, as the onboard loop does on its IMU).
  std::string controller_trigger = "timer";
  /// What the controller flies on: "truth" (ideal sensing, TRUTH) or "estimate" (ESTIMATE).
  std::string controller_input = "truth";
  /// Real time: spin this long before each deadline instead of sleeping [us] (0 = sleep).
  int spin_us = 0;
  /// Real time: a stream message received more than this after its due time is late [us];
  /// counted by each receiving process and by the launcher.
  int64_t late_threshold_us = 2000;
  /// 1: each process's LCM receive socket keeps only the channels the process subscribes, in
  /// the kernel, so a message wakes only the processes that take it (docs/timing.md "Timing");
  /// 0: LCM's own behaviour, every message wakes every process of the run.
  int channel_filter = 1;
  /// How long a process waits for the run's start (RUN_CONTROL start) before it gives up, named
  /// [s]: a process started by hand for a run that is refused, or whose launcher never starts or
  /// died, ends instead of waiting for ever. Kept above run.ready_timeout_s (the launcher's own
  /// wait for every READY), which the launcher checks.
  double start_wait_s = 120.0;
};

/// The `lockstep` section.
struct LockstepOptions {
  /// How long the plant waits for a due participant's STEP_ACK [ms] (wall clock).
  int ack_timeout_ms = 2000;
  /// The launcher's logger acknowledges every this much simulated time [ms], so that the
  /// run never gets further ahead of the log than this (no message is lost under load).
  double logger_period_ms = 10.0;
};

/// The `lockstep` section's parameters (defaults: LockstepOptions's).
const ParamTable<LockstepOptions>& lockstep_params();
/// The numeric process-level parameters of `run` (defaults: ProcessRunOptions's); the two
/// choices controller_trigger and controller_input are read by process_run_options_from().
const ParamTable<ProcessRunOptions>& process_run_params();

/// Reads the `lockstep` section (strict). @throws ConfigError naming the key.
LockstepOptions lockstep_options(const Scenario& scenario);

/// Reads the process-level options of `run`. @throws ConfigError naming the key.
ProcessRunOptions process_run_options(const Scenario& scenario);
/// The same from the `run` mapping itself, without finish(): the launcher reads its own keys
/// of the section from the same map.
ProcessRunOptions process_run_options_from(ConfigMap& run);

/// The files a scenario names besides its bases (which are merged into its tree): the lateral
/// and longitudinal models, the vehicle (the scenario's, and the one a model names), the
/// manoeuvre. Each as (what names it, absolute path), in a fixed order; a file named twice
/// comes once.
std::vector<std::pair<std::string, std::string>> named_files(const Scenario& scenario);

/// Digest of a resolved scenario (FNV-1a 64-bit, 16 hex digits) over its YAML text and the
/// content of every file it names (named_files()): a model or manoeuvre changed under the same
/// path changes it. Every process of a run puts it on its heartbeat and the launcher refuses a
/// process whose digest is not the run's; the run summary carries it (`config_digest`).
std::string scenario_digest(const Scenario& scenario);

/// Digest of a file's bytes, the same function as scenario_digest()'s (16 hex digits);
/// "unreadable" for a file that cannot be read, is no regular file or is above the bound of
/// `kind` (core/input_file.h; the rig's own program: InputKind::kProgram).
std::string file_digest(const std::string& path, InputKind kind = InputKind::kConfig);

/// Writes a tree as YAML text.
std::string to_yaml(const YAML::Node& node);

}  // namespace nimble
