#include "scenario/scenario.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <system_error>
#include <utility>

#include "contract/channels.h"
#include "core/input_file.h"
#include "core/yaml_input.h"
#include "scenario/fault_section.h"

namespace nimble {
namespace {

namespace fs = std::filesystem;

/// Keys whose values are file paths, relative to the file that sets them: the scenario's own
/// top-level files, and `base:` at any depth. A section key that happens to share one of the
/// top-level names (a plant option called `model`, say) is a value, not a path.
/// The key of the run's expected channel rates in a resolved scenario (Scenario::expected_rates_hz).
const std::string kExpectedRatesKey = "expected_rates_hz";

/// The deepest chain of `base:` files (scenario -> base -> its base ...) a scenario may have.
constexpr std::size_t kMaxBaseDepth = 16;

const std::set<std::string> kTopLevelPathKeys = {"model", "longitudinal_model", "vehicle", "manoeuvre", "base"};

/// Makes the path values of `node` absolute against `dir`; `top_level`: node is a scenario root.
void absolutise_paths(YAML::Node node, const fs::path& dir, bool top_level) {
  if (node.IsMap()) {
    for (auto it = node.begin(); it != node.end(); ++it) {
      const std::string key = it->first.as<std::string>();
      const bool path_key = key == "base" || (top_level && kTopLevelPathKeys.count(key));
      if (top_level && key == "participants" && it->second.IsMap()) {
        // Each participant's Python file, relative to the file that names it.
        for (auto entry : it->second) {
          YAML::Node python = entry.second.IsMap() ? entry.second["python"] : YAML::Node();
          if (python && python.IsScalar() && !python.Scalar().empty() && fs::path(python.Scalar()).is_relative()) {
            entry.second["python"] = (dir / python.Scalar()).lexically_normal().string();
          }
        }
      } else if (path_key && it->second.IsScalar()) {
        const fs::path p(it->second.Scalar());
        if (!p.empty() && p.is_relative()) it->second = (dir / p).lexically_normal().string();
      } else {
        absolutise_paths(it->second, dir, false);
      }
    }
  } else if (node.IsSequence()) {
    for (auto item : node) absolutise_paths(item, dir, false);
  }
}

/// A scenario or base file, read within the bounds of a configuration file (core/yaml_input.h).
YAML::Node load_yaml(const std::string& file, const std::string& referrer_key) {
  YAML::Node root = load_yaml_file(file, referrer_key);
  check_unique_keys(root, file);
  return root;
}

/// The file `path` names, for comparing the files of a chain of bases.
std::string file_identity(const std::string& path) {
  std::error_code ec;
  const fs::path p = fs::weakly_canonical(path, ec);
  return ec ? fs::absolute(path).lexically_normal().string() : p.string();
}

/// Merges `over` onto a copy of `under` (mappings recursively; everything else replaced).
YAML::Node merge(const YAML::Node& under, const YAML::Node& over) {
  if (!under.IsMap() || !over.IsMap()) return YAML::Clone(over);
  YAML::Node out = YAML::Clone(under);
  for (auto it = over.begin(); it != over.end(); ++it) {
    const std::string key = it->first.as<std::string>();
    out[key] = out[key] ? merge(out[key], it->second) : YAML::Clone(it->second);
  }
  return out;
}

std::string join_path(const std::string& a, const std::string& b) {
  return a.empty() ? b : b.empty() ? a : a + "." + b;
}

/// Records where each key of `node` (freshly parsed from `file`, so with line marks) is
/// written, as key paths under `mount`. `replace`: the new origins win over ones already
/// recorded (a later layer); otherwise the first recorded wins (an earlier, overriding layer).
void record_origins(const YAML::Node& node, const std::string& file, const std::string& mount, bool replace,
                    KeyOrigins* origins) {
  if (origins == nullptr || !node.IsMap()) return;
  for (auto it = node.begin(); it != node.end(); ++it) {
    if (!it->first.IsScalar()) continue;
    const std::string path = join_path(mount, it->first.Scalar());
    const KeyOrigin origin{file, it->first.Mark().is_null() ? -1 : it->first.Mark().line + 1};
    if (replace) {
      (*origins)[path] = origin;
    } else {
      origins->emplace(path, origin);
    }
    record_origins(it->second, file, path, replace, origins);
  }
}

/// Replaces every mapping that has `base:` by base merged with the mapping.
/// Resolves `base:` files in `node` (at `path` of `file`, which is mounted at `mount` of the
/// scenario); `at_root`: node is the scenario root. Each base file's keys are recorded in
/// `origins` where the files above it did not give them.
/// `chain`: the files from the scenario down to `file` (file last), to name a cycle whole.
/// `sections`: also resolve the bases of the mappings below `node`. A scenario standing on another
/// scenario (a root `base:`) is merged with it as written first, sections and their `base:` keys
/// included, and its sections resolved after: a section's base is the nearest scenario's (or
/// `--set <section>.base`'s), with every scenario's own keys of the section over it. Its sections'
/// chain is then the whole chain of scenarios (`scenarios` receives it), and an error in a section
/// names the file that wrote the key (`origins`, where given).
YAML::Node resolve_bases(YAML::Node node, const std::string& file, const std::string& path,
                         const std::vector<std::string>& chain, bool at_root, const std::string& mount,
                         KeyOrigins* origins, bool sections = true, std::vector<std::string>* scenarios = nullptr) {
  if (node.IsMap()) {
    YAML::Node out = YAML::Clone(node);
    std::vector<std::string> section_chain = chain;
    if (out["base"]) {
      const std::string base_key = path.empty() ? "base" : path + ".base";
      const auto written = origins != nullptr ? origins->find(join_path(mount, base_key)) : KeyOrigins::iterator{};
      const bool known = origins != nullptr && written != origins->end() && written->second.file != "--set";
      const std::string& where = known ? written->second.file : file;
      if (!out["base"].IsScalar()) throw ConfigError(where, base_key, "", "must be the name of a base file");
      const std::string base_file = out["base"].as<std::string>();
      std::vector<std::string> below = chain;
      below.push_back(base_file);
      const std::string identity = file_identity(base_file);
      for (std::size_t i = 0; i + 1 < below.size(); ++i) {
        if (file_identity(below[i]) != identity) continue;
        std::string cycle;
        for (std::size_t k = i; k < below.size(); ++k) cycle += (k > i ? " -> " : "") + below[k];
        throw ConfigError(where, base_key, base_file, "base files form a cycle: " + cycle);
      }
      if (below.size() > kMaxBaseDepth + 1) {
        throw ConfigError(where, base_key, base_file,
                          "base files nest deeper than " + std::to_string(kMaxBaseDepth) + " levels");
      }
      YAML::Node base = load_yaml(base_file, base_key);
      const std::string base_mount = join_path(mount, path);
      record_origins(base, base_file, base_mount, false, origins);
      absolutise_paths(base, fs::absolute(base_file).parent_path(), at_root);
      const bool scenario_chain = at_root && path.empty();
      base = resolve_bases(base, base_file, "", below, at_root, base_mount, origins, !scenario_chain,
                           scenario_chain ? &section_chain : nullptr);
      out.remove("base");
      out = merge(base, out);
    }
    if (scenarios != nullptr) *scenarios = section_chain;
    if (!sections) return out;
    for (auto it = out.begin(); it != out.end(); ++it) {
      const std::string key = it->first.as<std::string>();
      it->second =
          resolve_bases(it->second, file, path.empty() ? key : path + "." + key, section_chain, false, mount, origins);
    }
    return out;
  }
  return node;
}

}  // namespace

Override parse_override(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0) {
    throw ConfigError("--set", text, text, "must be key.path=value");
  }
  return Override{text.substr(0, eq), text.substr(eq + 1)};
}

namespace {

/// Whether an override names a section's base file (`--set sensing.base=FILE`).
bool is_base_override(const Override& o) {
  return o.key_path == "base" || (o.key_path.size() > 5 && o.key_path.compare(o.key_path.size() - 5, 5, ".base") == 0);
}

/// Applies the `--set <section>.base=FILE` overrides to the scenario as written, before its bases
/// are merged: the section then stands on FILE (relative to the working directory) instead of the
/// base it names, and its own keys still win over it, as with any base.
void apply_base_overrides(YAML::Node root, const std::vector<Override>& overrides, KeyOrigins* origins) {
  for (const auto& o : overrides) {
    if (!is_base_override(o)) continue;
    if (o.value.empty()) throw ConfigError("--set", o.key_path, o.value, "must be the name of a base file");
    YAML::Node node = root;
    std::string rest = o.key_path;
    for (auto dot = rest.find('.'); dot != std::string::npos; dot = rest.find('.')) {
      const std::string part = rest.substr(0, dot);
      YAML::Node next = node[part];
      if (next && !next.IsMap()) throw ConfigError("--set", o.key_path, o.value, "'" + part + "' is not a section");
      if (!next) node[part] = YAML::Node(YAML::NodeType::Map);
      node.reset(node[part]);
      rest.erase(0, dot + 1);
    }
    node["base"] = fs::absolute(o.value).lexically_normal().string();
    if (origins != nullptr) (*origins)[o.key_path] = KeyOrigin{"--set", -1};
  }
}

}  // namespace

YAML::Node load_scenario_tree(const std::string& file, const std::vector<Override>& overrides, KeyOrigins* origins) {
  YAML::Node root = load_yaml(file, "");
  if (!root.IsMap()) throw ConfigError(file, "", "", "a scenario must be a YAML mapping");
  record_origins(root, file, "", false, origins);
  absolutise_paths(root, fs::absolute(file).parent_path(), true);
  apply_base_overrides(root, overrides, origins);
  root = resolve_bases(root, file, "", {file}, true, "", origins);
  for (const auto& o : overrides) {
    if (is_base_override(o)) continue;
    YAML::Node value;
    try {
      value = load_yaml_text(o.value, "--set");
    } catch (const ConfigError& e) {
      const bool invalid = e.problem().rfind("not valid YAML", 0) == 0;
      throw ConfigError("--set", o.key_path, o.value, invalid ? "value is not valid YAML" : e.problem());
    }
    // Walk down the dotted path, creating mappings as needed.
    std::vector<std::string> parts;
    std::string part;
    for (const char c : o.key_path) {
      if (c == '.') {
        parts.push_back(part);
        part.clear();
      } else {
        part += c;
      }
    }
    parts.push_back(part);
    std::vector<YAML::Node> chain{root};
    for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
      YAML::Node next = chain.back()[parts[i]];
      if (next && !next.IsMap()) {
        throw ConfigError("--set", o.key_path, o.value, "'" + parts[i] + "' is not a section");
      }
      chain.push_back(next);
    }
    chain.back()[parts.back()] = value;
    if (origins != nullptr) {
      (*origins)[o.key_path] = KeyOrigin{"--set", -1};
      // Keys inside a mapping given on the command line come from there too.
      KeyOrigins inner;
      record_origins(value, "--set", o.key_path, true, &inner);
      for (auto& [path, origin] : inner) (*origins)[path] = KeyOrigin{"--set", -1};
    }
  }
  return root;
}

ConfigError locate_error(const ConfigError& error, const std::string& scenario_file, const KeyOrigins& origins) {
  if (error.file() != scenario_file || error.key().empty()) return error;
  // The key itself, or the nearest enclosing key (or list, for "terms[0].expression") with a
  // recorded origin.
  std::string path = error.key();
  for (;;) {
    const auto it = origins.find(path);
    if (it != origins.end()) {
      return ConfigError(it->second.file, error.key(), error.value(), error.problem(), it->second.line);
    }
    const auto dot = path.find_last_of(".[");
    if (dot == std::string::npos) return error;
    path.erase(dot);
  }
}

const std::vector<std::string>& scenario_section_keys() {
  // The IMU, motion-capture and EKF settings live under sensing (sensing.imu, sensing.mocap,
  // sensing.ekf): a top-level imu, mocap or estimator section would be read by nobody.
  static const std::vector<std::string> keys = {"plant", "controller", "sensing", "can_bridge", "lockstep",
                                                "run",   "summary",    "hosts",   "pilot",      "cluster"};
  return keys;
}

double Scenario::expected_rate(const std::string& channel) const {
  const auto it = expected_rates_hz.find(channel);
  return it == expected_rates_hz.end() ? 0.0 : it->second;
}

void set_expected_rates(Scenario& scenario, const std::map<std::string, double>& rates_hz) {
  scenario.expected_rates_hz = rates_hz;
  YAML::Node node(YAML::NodeType::Map);
  for (const auto& [channel, hz] : rates_hz) node[channel] = hz;
  scenario.root[kExpectedRatesKey] = node;
}

bool Scenario::runs(const std::string& process) const {
  return std::find(processes.begin(), processes.end(), process) != processes.end();
}

ConfigMap Scenario::section(const std::string& name) const {
  const YAML::Node found = root[name];
  if (found) return ConfigMap(found, file, name);
  return ConfigMap(YAML::Node(YAML::NodeType::Map), file, name);
}

const std::vector<std::string>& replaceable_processes() {
  static const std::vector<std::string> processes = {"controller", "mocap", "estimator"};
  return processes;
}

namespace {

/// True if `name` is a Python identifier of ASCII letters, digits and underscores.
bool python_identifier(const std::string& name) {
  if (name.empty() || std::isdigit(static_cast<unsigned char>(name[0]))) return false;
  return std::all_of(name.begin(), name.end(),
                     [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; });
}

/// True if the Python source `text` defines `class_name` at its top level (`class Name:` or
/// `class Name(Base):` at the start of a line): what the scenario can check without Python.
bool defines_class(const std::string& text, const std::string& class_name) {
  std::size_t at = 0;
  while (at < text.size()) {
    const std::size_t end = std::min(text.find('\n', at), text.size());
    const std::string line = text.substr(at, end - at);
    at = end + 1;
    if (line.rfind("class ", 0) != 0) continue;
    std::size_t i = 6;
    while (i < line.size() && line[i] == ' ') ++i;
    if (line.compare(i, class_name.size(), class_name) != 0) continue;
    i += class_name.size();
    while (i < line.size() && line[i] == ' ') ++i;
    if (i < line.size() && (line[i] == '(' || line[i] == ':')) return true;
  }
  return false;
}

/// The `participants` section: {process: {python: FILE, class: NAME, arguments: {...}}}.
std::map<std::string, ParticipantSpec> participants_from(const YAML::Node& node, const std::string& file,
                                                         const std::vector<std::string>& processes) {
  if (!node.IsMap()) {
    throw ConfigError(file, "participants", "",
                      "must be a mapping of process name to {python: FILE, class: NAME}, e.g. "
                      "controller: {python: my_controller.py, class: MyController}");
  }
  std::map<std::string, ParticipantSpec> out;
  const auto& replaceable = replaceable_processes();
  for (const auto& entry : node) {
    const std::string process = entry.first.as<std::string>();
    const std::string key = "participants." + process;
    if (std::find(replaceable.begin(), replaceable.end(), process) == replaceable.end()) {
      throw ConfigError(file, key, "",
                        "a participant of one's own replaces the controller, mocap or estimator (the plant is the "
                        "vehicle and the lockstep master; the CAN bridge's sides speak SocketCAN)");
    }
    if (std::find(processes.begin(), processes.end(), process) == processes.end()) {
      throw ConfigError(file, key, "", "'" + process + "' is not one of the run's processes: list it in processes");
    }
    if (!entry.second.IsMap()) throw ConfigError(file, key, "", "must be a mapping {python: FILE, class: NAME}");
    ConfigMap m(entry.second, file, key);
    ParticipantSpec spec;
    spec.python_file = m.get_string("python");
    spec.class_name = m.get_string("class");
    if (m.has("arguments")) {
      spec.arguments = m.get_node("arguments");
      if (!spec.arguments.IsMap() && !spec.arguments.IsNull()) {
        m.fail("arguments", "must be a mapping of the class's keyword arguments, e.g. {kp: 0.5}");
      }
    }
    m.finish();
    if (!python_identifier(spec.class_name)) m.fail("class", "'" + spec.class_name + "' is not a Python class name");
    if (fs::path(spec.python_file).extension() != ".py") m.fail("python", "must be a Python file (*.py)");
    std::string text;
    try {
      text = read_input_file(spec.python_file, InputKind::kConfig);
    } catch (const InputFileError& e) {
      m.fail("python", e.what());
    }
    if (!defines_class(text, spec.class_name)) {
      m.fail("class", "'" + spec.python_file + "' defines no top-level class " + spec.class_name + " (a line `class " +
                          spec.class_name + "(nimble_rig.Participant):`)");
    }
    out[process] = std::move(spec);
  }
  return out;
}

}  // namespace

Scenario scenario_from_tree(const YAML::Node& root, const std::string& file) {
  ConfigMap map(root, file, "");
  Scenario s;
  s.file = file;
  s.root = root;
  s.name = map.get_string("name");
  s.description = map.get_string_or("description", "");
  s.duration_s = map.get_double("duration_s", Range{0.0, 24 * 3600.0, true, false});
  s.clock = map.get_enum("clock", {"realtime", "lockstep", "inprocess"});
  s.seed = static_cast<uint64_t>(map.get_int("seed", Range::closed(0, 9.0e15)));
  s.model_file = map.get_string("model");
  s.longitudinal_model_file = map.get_string_or("longitudinal_model", "");
  s.vehicle_file = map.get_string_or("vehicle", "");
  s.processes = map.get_string_list("processes");
  if (map.has("actuator_link")) s.actuator_link = map.get_enum("actuator_link", {"lcm", "can"});
  const std::set<std::string> known = {"plant", "controller", "mocap", "estimator", "can_flight", "can_rig"};
  std::set<std::string> seen;
  for (const auto& p : s.processes) {
    if (!known.count(p)) {
      map.fail("processes",
               "unknown process '" + p + "' (known: plant, controller, mocap, estimator, can_flight, can_rig)");
    }
    if (!seen.insert(p).second) map.fail("processes", "process '" + p + "' listed twice");
    if ((p == "can_flight" || p == "can_rig") && s.actuator_link != "can") {
      map.fail("processes", "process '" + p + "' is a side of the CAN bridge: it needs actuator_link: can");
    }
  }
  if (!seen.count("plant")) map.fail("processes", "a run needs the plant");
  if (s.actuator_link == "can") {
    for (const char* side : {"can_flight", "can_rig"}) {
      if (!seen.count(side)) s.processes.push_back(side);
    }
  }
  for (const auto& key : scenario_section_keys()) {
    if (map.has(key)) map.get_node(key);  // mark as known; owners validate the content
  }
  if (map.has("manoeuvre")) map.get_string("manoeuvre");
  if (map.has(kExpectedRatesKey)) {
    const YAML::Node node = map.get_node(kExpectedRatesKey);
    if (!node.IsMap()) map.fail(kExpectedRatesKey, "must be a mapping of channel name to rate [Hz]");
    ConfigMap rates(node, file, kExpectedRatesKey);
    for (const auto& entry : node) {
      const std::string channel = entry.first.as<std::string>();
      if (contract::find_channel(channel) == nullptr) {
        rates.fail(channel, "not a channel of the rig's contract (contract/channels.h)");
      }
      s.expected_rates_hz[channel] = rates.get_double(channel, Range::positive());
    }
    rates.finish();
  }
  if (map.has("participants")) s.participants = participants_from(map.get_node("participants"), file, s.processes);
  if (map.has("faults")) {
    s.faults = faults_from(map.get_node("faults"), file, s.processes, s.actuator_link == "can", s.duration_s);
  }
  map.finish();
  for (const auto& f : {s.model_file, s.longitudinal_model_file, s.vehicle_file}) {
    if (f.empty()) continue;
    std::error_code ec;
    const bool found = fs::exists(f, ec);
    // A name the file system refuses (too long, a component that is not a folder) is named as such.
    if (ec && ec != std::errc::no_such_file_or_directory)
      throw ConfigError(file, "model", f, "cannot be looked up: " + ec.message());
    if (!found) throw ConfigError(file, "model", f, "file not found");
  }
  return s;
}

std::string plant_command_channel(const Scenario& scenario) {
  return contract::plant_command_channel(scenario.actuator_link == "can");
}

std::string manoeuvre_file(const Scenario& scenario, bool required, const std::string& why) {
  const YAML::Node m = scenario.root["manoeuvre"];
  if (!m || m.IsNull()) {
    if (required) throw ConfigError(scenario.file, "manoeuvre", "", "missing required key: " + why);
    return "";
  }
  if (!m.IsScalar() || m.Scalar().empty()) {
    throw ConfigError(scenario.file, "manoeuvre", yaml_text(m), "must be the path of a manoeuvre file");
  }
  return m.Scalar();
}

Scenario load_scenario(const std::string& file, const std::vector<Override>& overrides) {
  KeyOrigins origins;
  const YAML::Node root = load_scenario_tree(file, overrides, &origins);
  try {
    Scenario s = scenario_from_tree(root, file);
    s.origins = std::move(origins);
    return s;
  } catch (const ConfigError& e) {
    throw locate_error(e, file, origins);
  }
}

const ParamTable<LockstepOptions>& lockstep_params() {
  using C = LockstepOptions;
  static const ParamTable<C> table = {
      {"ack_timeout_ms", &C::ack_timeout_ms, Range::closed(10, 600000), "ms",
       "how long the plant waits for a due participant's STEP_ACK (wall clock)"},
      {"logger_period_ms", &C::logger_period_ms, Range::closed(1.0, 1000.0), "ms",
       "the launcher's recorder acknowledges every this much simulated time, so the run never outpaces the log"},
  };
  return table;
}

const ParamTable<ProcessRunOptions>& process_run_params() {
  using C = ProcessRunOptions;
  static const ParamTable<C> table = {
      {"realtime_priority", &C::realtime_priority, Range::closed(0, 99), "-",
       "real time: SCHED_FIFO priority of the rig's processes, 0 = default scheduler"},
      {"spin_us", &C::spin_us, Range::closed(0, 1000), "us",
       "real time: spin this long before each deadline instead of sleeping (0 = sleep)"},
      {"late_threshold_us", &C::late_threshold_us, Range::positive(), "us",
       "real time: a stream message received later than this after its due time is late"},
      {"channel_filter", &C::channel_filter, Range::closed(0, 1), "-",
       "1: each process's LCM socket drops, in the kernel, the channels the process does not take; 0: every message "
       "wakes every process"},
      {"start_wait_s", &C::start_wait_s, Range{0.0, 86400.0, true, false}, "s",
       "a process waits this long for the run's start, then gives up, named (one started by hand for a run that was "
       "refused or whose launcher is gone); above run.ready_timeout_s"},
  };
  return table;
}

LockstepOptions lockstep_options(const Scenario& scenario) {
  LockstepOptions o;
  ConfigMap m = scenario.section("lockstep");
  read_params(m, lockstep_params(), o);
  m.finish();
  return o;
}

ProcessRunOptions process_run_options_from(ConfigMap& run) {
  ProcessRunOptions o;
  read_params(run, process_run_params(), o);
  if (run.has("controller_trigger")) o.controller_trigger = run.get_enum("controller_trigger", {"timer", "state"});
  if (run.has("controller_input")) o.controller_input = run.get_enum("controller_input", {"truth", "estimate"});
  return o;
}

ProcessRunOptions process_run_options(const Scenario& scenario) {
  ConfigMap run = scenario.section("run");
  return process_run_options_from(run);
}

std::vector<std::pair<std::string, std::string>> named_files(const Scenario& scenario) {
  std::vector<std::pair<std::string, std::string>> files;
  const auto add = [&files](const std::string& what, const std::string& path) {
    if (path.empty()) return;
    const std::string absolute = fs::absolute(path).lexically_normal().string();
    for (const auto& f : files) {
      if (f.second == absolute) return;
    }
    files.emplace_back(what, absolute);
  };
  // The vehicle a model file names, relative to the model (core/model.h); none if unreadable.
  const auto model_vehicle = [](const std::string& model) -> std::string {
    try {
      const YAML::Node root = load_yaml_file(model);
      if (root.IsMap() && root["vehicle"] && root["vehicle"].IsScalar()) {
        const fs::path v(root["vehicle"].Scalar());
        return v.is_relative() ? (fs::path(model).parent_path() / v).string() : v.string();
      }
    } catch (const YAML::Exception&) {
    } catch (const ConfigError&) {
    }
    return "";
  };
  add("model", scenario.model_file);
  if (!scenario.model_file.empty()) add("model.vehicle", model_vehicle(scenario.model_file));
  add("longitudinal_model", scenario.longitudinal_model_file);
  if (!scenario.longitudinal_model_file.empty()) {
    add("longitudinal_model.vehicle", model_vehicle(scenario.longitudinal_model_file));
  }
  add("vehicle", scenario.vehicle_file);
  if (scenario.root["manoeuvre"] && scenario.root["manoeuvre"].IsScalar()) {
    add("manoeuvre", scenario.root["manoeuvre"].Scalar());
  }
  for (const auto& [process, spec] : scenario.participants)
    add("participants." + process + ".python", spec.python_file);
  return files;
}

namespace {

/// The digests' FNV-1a over bytes fed in turn.
struct Digest {
  uint64_t h = 1469598103934665603ULL;
  void feed(const std::string& bytes) {
    for (const unsigned char c : bytes) {
      h ^= c;
      h *= 1099511628211ULL;
    }
  }
  std::string hex() const {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
    return buf;
  }
};

}  // namespace

std::string file_digest(const std::string& path, InputKind kind) {
  Digest d;
  try {
    d.feed(read_input_file(path, kind));
  } catch (const InputFileError&) {
    return "unreadable";
  }
  return d.hex();
}

std::string scenario_digest(const Scenario& scenario) {
  Digest d;
  const auto feed = [&d](const std::string& bytes) { d.feed(bytes); };
  feed(to_yaml(scenario.root));
  for (const auto& [what, path] : named_files(scenario)) {
    // A file that cannot be read digests as such (its loader names the problem).
    std::string content;
    try {
      content = read_input_file(path, InputKind::kConfig);
    } catch (const InputFileError&) {
      content = "(unreadable)";
    }
    feed(what + '\0' + path + '\0' + content + '\0');
  }
  return d.hex();
}

std::string to_yaml(const YAML::Node& node) {
  YAML::Emitter out;
  out << node;
  return std::string(out.c_str()) + "\n";
}

}  // namespace nimble
