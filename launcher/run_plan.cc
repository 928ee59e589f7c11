#include "launcher/run_plan.h"

#include <sched.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "can_bridge/bridge_config.h"
#include "contract/channels.h"
#include "contract/rates.h"
#include "core/output_file.h"
#include "launcher/cluster_section.h"
#include "launcher/scenario_check.h"

namespace nimble::launcher {
namespace {

namespace fs = std::filesystem;

std::vector<int> read_cpu_list(ConfigMap& m, const std::string& key) {
  std::vector<int> cpus;
  if (!m.has(key)) return cpus;
  const YAML::Node list = m.get_node(key);
  if (!list.IsSequence()) m.fail(key, "must be a list of CPU numbers, e.g. [0]");
  for (const auto& item : list) {
    int cpu = -1;
    try {
      cpu = item.as<int>();
    } catch (const YAML::Exception&) {
      m.fail(key, "must be a list of CPU numbers, e.g. [0]");
    }
    if (cpu < 0 || cpu >= CPU_SETSIZE) m.fail(key, "CPU numbers must be in [0, " + std::to_string(CPU_SETSIZE) + ")");
    cpus.push_back(cpu);
  }
  return cpus;
}

LaunchConfig launch_config_from(const Scenario& s) {
  LaunchConfig c;
  ConfigMap m = s.section("run");
  read_params(m, launch_params(), c);
  c.lcm_url = m.get_string_or("lcm_url", c.lcm_url);
  c.python = m.get_string_or("python", c.python);
  if (!s.participants.empty() && ::access(c.python.c_str(), X_OK) != 0) {
    m.fail("python", "'" + c.python + "' is not an executable Python interpreter (" + std::strerror(errno) +
                         "): the scenario's participants run under it");
  }
  c.network_namespace = m.has("network_namespace") ? m.get_enum("network_namespace", {"auto", "always", "never"})
                                                   : m.get_string_or("network_namespace", "auto");
  // The processes' own keys of the section, checked where they are defined.
  const ProcessRunOptions processes = process_run_options_from(m);
  if (processes.start_wait_s <= c.ready_timeout_s) {
    m.fail("start_wait_s",
           "must be above run.ready_timeout_s (" + std::to_string(c.ready_timeout_s) +
               " s): a process would give up waiting for the start before the launcher stops waiting for it");
  }
  c.rig_cpus = read_cpu_list(m, "rig_cpus");
  c.lockstep_cpus = read_cpu_list(m, "lockstep_cpus");
  c.launcher_cpus = read_cpu_list(m, "launcher_cpus");
  if (m.has("external_processes")) {
    c.external_processes = m.get_string_list("external_processes");
    for (const auto& p : c.external_processes) {
      if (!s.runs(p)) {
        m.fail("external_processes", "'" + p + "' is not one of the run's processes");
      }
    }
  }
  m.finish();
  return c;
}

JudgeConfig judge_config_from(const Scenario& s) {
  JudgeConfig c;
  ConfigMap m = s.section("summary");
  read_params(m, judge_params(), c);
  m.finish();
  return c;
}

std::string timestamp() {
  const std::time_t now = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y%m%d-%H%M%S", std::localtime(&now));
  return buf;
}

}  // namespace

const ParamTable<LaunchConfig>& launch_params() {
  using C = LaunchConfig;
  static const ParamTable<C> table = {
      {"ready_timeout_s", &C::ready_timeout_s, Range{0.0, 600.0, true, false}, "s",
       "every process must report READY within this"},
      {"stop_grace_s", &C::stop_grace_s, Range::closed(0.0, 60.0), "s", "after RUN_CONTROL stop, before SIGTERM"},
      {"stall_timeout_s", &C::stall_timeout_s, Range{0.0, 3600.0, true, false}, "s",
       "lockstep: no new TRUTH for this long (wall clock) is a failure"},
      {"start_delay_s", &C::start_delay_s, Range::closed(0.0, 10.0), "s",
       "real time: simulated time 0 lies this far after the start command"},
      {"heartbeat_timeout_s", &C::heartbeat_timeout_s, Range{0.0, 600.0, true, false}, "s",
       "a running process silent for this long (wall clock) is lost: HEARTBEAT_LOST, the run fails"},
  };
  return table;
}

const ParamTable<JudgeConfig>& judge_params() {
  using C = JudgeConfig;
  static const ParamTable<C> table = {
      {"max_phi_deg", &C::max_phi_deg, Range{0.0, 180.0, true, false}, "deg",
       "beyond this roll the vehicle is not controlled"},
      {"max_theta_deg", &C::max_theta_deg, Range{0.0, 90.0, true, false}, "deg",
       "beyond this pitch (the pitch set-point limit) neither"},
      {"hover_phi_deg", &C::hover_phi_deg, Range::positive(), "deg", "final |phi| within this: returned to hover"},
      {"hover_p_radps", &C::hover_p_radps, Range::positive(), "rad/s", "final |p| within this: returned to hover"},
      {"hover_v_mps", &C::hover_v_mps, Range::positive(), "m/s", "final |v| within this: returned to hover"},
      {"max_late_fraction", &C::max_late_fraction, Range::closed(0.0, 1.0), "-",
       "real time: more of a channel's messages late at a receiving process than this is real-time degraded"},
      {"trace_hz", &C::trace_hz, Range::closed(0.0, 1000.0), "Hz",
       "the JSON report's trace: p, v and phi of TRUTH at this rate of rig time (0: none; rig sweep --report sets it)"},
      {"max_overrun_fraction", &C::max_overrun_fraction, Range::closed(0.0, 1.0), "-",
       "real time: more of a process's cycles overrun than this is real-time degraded"},
      {"max_tracking_rms_deg", &C::max_tracking_rms_deg, Range{0.0, 180.0, true, false}, "deg",
       "RMS over the run of the roll tracking error (the controller's roll reference - the true roll) beyond this: not "
       "tracking (nominal flights 10.7 at most, within the loop's margins 14.7)"},
      {"max_tracking_error_deg", &C::max_tracking_error_deg, Range{0.0, 180.0, true, false}, "deg",
       "largest |roll tracking error| beyond this: not tracking (nominal flights 56.1 at most, within the loop's "
       "margins 76)"},
      {"oscillation_amplitude_deg", &C::oscillation_amplitude_deg, Range::positive(), "deg",
       "roll oscillation: every half-cycle's peak of the tracking error at least this (within the loop's margins 2.6 "
       "at most; beyond them 7 and more)"},
      {"oscillation_cycles", &C::oscillation_cycles, Range::closed(2.0, 100.0), "-",
       "roll oscillation: this many cycles in a row"},
      {"oscillation_period_tolerance", &C::oscillation_period_tolerance, Range{0.0, 1.0, true, true}, "-",
       "roll oscillation: every full period within this fraction of their mean"},
      {"oscillation_max_damping", &C::oscillation_max_damping, Range{-1.0, 1.0, true, true}, "-",
       "roll oscillation: its amplitude decays with a damping ratio below this (within the loop's margins 0.0057 and "
       "more; beyond them 0.0010 and less)"},
      {"oscillation_reference_still_deg", &C::oscillation_reference_still_deg, Range{0.0, 180.0, true, false}, "deg",
       "roll oscillation: counts only half-cycles in which the roll reference moved less than this (the loop's own "
       "motion, not the manoeuvre's)"},
  };
  return table;
}

RunPlan load_run_plan(const RunOptions& options) {
  std::vector<Override> overrides = options.overrides;
  if (options.clock) {
    if (*options.clock != kClockRealtime && *options.clock != kClockLockstep && *options.clock != kClockInprocess) {
      throw ConfigError("--clock", "clock", *options.clock, "must be realtime, lockstep or inprocess");
    }
    overrides.push_back({"clock", *options.clock});
  }
  if (options.seed) overrides.push_back({"seed", std::to_string(*options.seed)});
  RunPlan plan;
  plan.scenario = load_scenario(options.scenario_file, overrides);
  try {
    validate_process_sections(plan.scenario);
    plan.logger_period_ms = lockstep_options(plan.scenario).logger_period_ms;
    plan.launch = launch_config_from(plan.scenario);
    plan.judge = judge_config_from(plan.scenario);
    cluster_settings_from(plan.scenario);  // read by rig sweep --backend slurm; checked here
    plan.rates = process_rates(plan.scenario);
    // What every process expects of its inputs: the stream channels' rates of this run.
    std::map<std::string, double> stream_hz;
    for (const auto& [channel, hz] : contract::expected_rates(plan.rates, contract::RunShape{})) {
      if (hz > 0 && contract::due_in_sim_time(channel)) stream_hz[channel] = hz;
    }
    set_expected_rates(plan.scenario, stream_hz);
    plan.hosts = host_placement_from(plan.scenario, plan.launch);
    add_by_hand_processes(plan.hosts, plan.launch.external_processes);
  } catch (const ConfigError& e) {
    // Name the file and line the key was written on (a base file), or --set.
    throw locate_error(e, plan.scenario.file, plan.scenario.origins);
  }
  return plan;
}

std::string log_file_for(const RunPlan& plan, const RunOptions& options) {
  if (!options.log_file.empty()) return options.log_file;
  return "rig_logs/" + plan.scenario.name + "-" + timestamp() + ".lcmlog";
}

void place_candump_log(RunPlan& plan, const std::string& log_file) {
  if (plan.scenario.actuator_link != "can") return;
  ConfigMap section = plan.scenario.section("can_bridge");
  const can::CanBridgeConfig cc = can::can_bridge_config_from(section);
  if (cc.candump_log && cc.candump_file.empty()) {
    plan.scenario.root["can_bridge"]["candump_file"] = fs::absolute(log_file + ".candump").string();
  }
}

std::string write_resolved_scenario(const RunPlan& plan, const std::string& log_file) {
  std::error_code ec;
  if (fs::path(log_file).has_parent_path()) fs::create_directories(fs::path(log_file).parent_path(), ec);
  const std::string resolved_file = log_file + ".scenario.yaml";
  write_file(resolved_file, "# Resolved scenario of this run (bases merged, overrides applied): " + plan.scenario.file +
                                "\n" + to_yaml(plan.scenario.root));
  return resolved_file;
}

}  // namespace nimble::launcher
