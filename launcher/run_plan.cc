#include "launcher/run_plan.h"

#include <sched.h>

#include <ctime>
#include <filesystem>
#include <fstream>
#include <stdexcept>

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
  c.ready_timeout_s = m.get_double_or("ready_timeout_s", c.ready_timeout_s, Range{0.0, 600.0, true, false});
  c.stop_grace_s = m.get_double_or("stop_grace_s", c.stop_grace_s, Range::closed(0.0, 60.0));
  c.stall_timeout_s = m.get_double_or("stall_timeout_s", c.stall_timeout_s, Range{0.0, 3600.0, true, false});
  c.start_delay_s = m.get_double_or("start_delay_s", c.start_delay_s, Range::closed(0.0, 10.0));
  c.lcm_url = m.get_string_or("lcm_url", c.lcm_url);
  c.network_namespace = m.has("network_namespace") ? m.get_enum("network_namespace", {"auto", "always", "never"})
                                                   : m.get_string_or("network_namespace", "auto");
  c.late_threshold_us = static_cast<int64_t>(m.get_double_or("late_threshold_us", 2000, Range::positive()));
  if (m.has("realtime_priority")) m.get_int("realtime_priority", Range::closed(0, 99));
  if (m.has("controller_trigger")) m.get_enum("controller_trigger", {"timer", "state"});
  if (m.has("spin_us")) m.get_int("spin_us", Range::closed(0, 1000));
  if (m.has("controller_input")) m.get_enum("controller_input", {"truth", "estimate"});
  c.rig_cpus = read_cpu_list(m, "rig_cpus");
  c.launcher_cpus = read_cpu_list(m, "launcher_cpus");
  m.finish();
  return c;
}

JudgeConfig judge_config_from(const Scenario& s) {
  JudgeConfig c;
  ConfigMap m = s.section("summary");
  c.max_phi_deg = m.get_double_or("max_phi_deg", c.max_phi_deg, Range{0.0, 180.0, true, false});
  c.max_theta_deg = m.get_double_or("max_theta_deg", c.max_theta_deg, Range{0.0, 90.0, true, false});
  c.hover_phi_deg = m.get_double_or("hover_phi_deg", c.hover_phi_deg, Range::positive());
  c.hover_p_radps = m.get_double_or("hover_p_radps", c.hover_p_radps, Range::positive());
  c.hover_v_mps = m.get_double_or("hover_v_mps", c.hover_v_mps, Range::positive());
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
  validate_process_sections(plan.scenario);
  plan.logger_period_ms = lockstep_options(plan.scenario).logger_period_ms;
  plan.launch = launch_config_from(plan.scenario);
  plan.judge = judge_config_from(plan.scenario);
  plan.rates = process_rates(plan.scenario);
  return plan;
}

std::string log_file_for(const RunPlan& plan, const RunOptions& options) {
  if (!options.log_file.empty()) return options.log_file;
  return "rig_logs/" + plan.scenario.name + "-" + timestamp() + ".lcmlog";
}

std::string write_resolved_scenario(const RunPlan& plan, const std::string& log_file) {
  std::error_code ec;
  if (fs::path(log_file).has_parent_path()) fs::create_directories(fs::path(log_file).parent_path(), ec);
  const std::string resolved_file = log_file + ".scenario.yaml";
  std::ofstream out(resolved_file);
  out << "# Resolved scenario of this run (bases merged, overrides applied): " << plan.scenario.file << "\n";
  out << to_yaml(plan.scenario.root);
  if (!out) throw std::runtime_error("cannot write " + resolved_file);
  return resolved_file;
}

}  // namespace nimble::launcher
