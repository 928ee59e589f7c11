#include "launcher/launcher.h"

#include <fcntl.h>
#include <signal.h>
#include <sched.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>

#include <lcm/lcm-cpp.hpp>
#include <nimble/heartbeat_t.hpp>
#include <nimble/rig_clock_t.hpp>
#include <nimble/run_control_t.hpp>
#include <nimble/step_ack_t.hpp>

#include "can_bridge/bridge_config.h"
#include "contract/channels.h"
#include "contract/rates.h"
#include "core/json_writer.h"
#include "launcher/netns.h"
#include "launcher/run_monitor.h"
#include "launcher/validate.h"
#include "transport/bus.h"
#include "transport/clock.h"

namespace nimble::launcher {
namespace {

namespace fs = std::filesystem;
using transport::monotonic_ns;

volatile std::sig_atomic_t g_interrupted = 0;
extern "C" void on_interrupt(int) { g_interrupted = 1; }

/// Settings of the launcher itself (scenario section `run`).
struct LaunchConfig {
  double ready_timeout_s = 15.0;   ///< every process must report READY within this [s]
  double stop_grace_s = 2.0;       ///< after RUN_CONTROL stop, before SIGTERM [s]
  double stall_timeout_s = 10.0;   ///< lockstep: no simulated progress for this long is a failure [s]
  double start_delay_s = 0.05;     ///< real time: t0 lies this far after the start command [s]
  std::string lcm_url = "auto";    ///< "auto": private namespace (or host multicast) per run
  std::string network_namespace = "auto";  ///< auto | always | never
  int64_t late_threshold_us = 2000;
  std::vector<int> rig_cpus;       ///< CPUs for the rig's processes (empty: no pinning)
  std::vector<int> launcher_cpus;  ///< CPUs for the launcher itself (empty: no pinning)
};

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

/// Pins the calling process to `cpus` that exist; returns a note when some do not.
std::string pin_to(const std::vector<int>& cpus) {
  if (cpus.empty()) return "";
  const int online = static_cast<int>(::sysconf(_SC_NPROCESSORS_ONLN));
  cpu_set_t set;
  CPU_ZERO(&set);
  int used = 0;
  for (const int c : cpus) {
    if (c < online) {
      CPU_SET(c, &set);
      ++used;
    }
  }
  if (used == 0) return "none of the CPUs asked for exist on this machine (" + std::to_string(online) + " online)";
  if (::sched_setaffinity(0, sizeof set, &set) != 0) return std::string("sched_setaffinity: ") + std::strerror(errno);
  return used < static_cast<int>(cpus.size()) ? "some CPUs asked for do not exist; pinned to the others" : "";
}

/// Judgement of the flight (scenario section `summary`).
struct JudgeConfig {
  double max_phi_deg = 80.0;        ///< beyond this roll the vehicle is not controlled
  double max_theta_deg = 60.0;      ///< beyond this pitch (the pitch set-point limit) neither
  double hover_phi_deg = 5.0;       ///< final |phi| for "returned to hover"
  double hover_p_radps = 0.5;       ///< final |p| for "returned to hover"
  double hover_v_mps = 0.3;         ///< final |v| for "returned to hover"
};

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

std::string self_dir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string(".") : exe.parent_path().string();
}

struct Child {
  std::string name;
  pid_t pid = -1;
  std::string output_file;
  bool exited = false;
  int exit_code = -1;
  int signal = 0;
};

pid_t spawn(const std::string& exe, const std::vector<std::string>& args, const std::string& output_file,
            const std::vector<int>& cpus) {
  const pid_t pid = ::fork();
  if (pid != 0) return pid;
  pin_to(cpus);
  // Child: die with the launcher, write output to its own file.
  ::prctl(PR_SET_PDEATHSIG, SIGTERM);
  ::signal(SIGINT, SIG_IGN);  // the launcher handles Ctrl-C and stops the run in order
  const int fd = ::open(output_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd >= 0) {
    ::dup2(fd, STDOUT_FILENO);
    ::dup2(fd, STDERR_FILENO);
    ::close(fd);
  }
  std::vector<char*> argv;
  argv.push_back(const_cast<char*>(exe.c_str()));
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  ::execv(exe.c_str(), argv.data());
  std::fprintf(stderr, "cannot execute %s: %s\n", exe.c_str(), std::strerror(errno));
  ::_exit(127);
}

std::string tail_of(const std::string& file, int lines) {
  std::ifstream in(file);
  std::vector<std::string> all;
  for (std::string line; std::getline(in, line);) all.push_back(line);
  std::string out;
  for (std::size_t i = all.size() > static_cast<std::size_t>(lines) ? all.size() - lines : 0; i < all.size(); ++i) {
    out += "    | " + all[i] + "\n";
  }
  return out;
}

std::string describe_exit(const Child& c) {
  if (c.signal != 0) return "was killed by signal " + std::to_string(c.signal) + " (" + strsignal(c.signal) + ")";
  return "exited with code " + std::to_string(c.exit_code);
}

/// Reaps children that have exited; returns the first one newly found dead (or nullptr).
Child* reap(std::vector<Child>& children) {
  Child* first = nullptr;
  for (auto& c : children) {
    if (c.exited || c.pid <= 0) continue;
    int status = 0;
    if (::waitpid(c.pid, &status, WNOHANG) == c.pid) {
      c.exited = true;
      if (WIFEXITED(status)) c.exit_code = WEXITSTATUS(status);
      if (WIFSIGNALED(status)) c.signal = WTERMSIG(status);
      if (!first) first = &c;
    }
  }
  return first;
}

/// The executable of a rig process: nimble_<name>; both sides of the CAN bridge run
/// nimble_can_bridge (their name selects the side).
std::string executable_of(const std::string& process) {
  if (process == can::kFlightProcess || process == can::kRigProcess) return "nimble_can_bridge";
  return "nimble_" + process;
}

void print_summary(std::ostream& out, const Scenario& s, const std::string& url, const std::string& ns_detail,
                   const std::string& log_file, double sim_s, double wall_s,
                   const std::map<std::string, ChannelSummary>& channels, const RunMonitor& mon,
                   const std::vector<Child>& children, bool controlled, bool hover, const std::string& verdict) {
  const FlightSummary& f = mon.flight();
  char line[256];
  out << "\n== run summary: " << s.name << " ==\n";
  out << "clock      " << s.clock << ", seed " << s.seed << "\n";
  out << "transport  " << url << (ns_detail.empty() ? "" : "  (" + ns_detail + ")") << "\n";
  out << "log        " << log_file << "\n";
  std::snprintf(line, sizeof line, "time       simulated %.3f s, wall %.3f s (%.2fx real time)\n", sim_s, wall_s,
                wall_s > 0 ? sim_s / wall_s : 0.0);
  out << line;
  out << "\nchannel              count    rate [Hz]  expected   drops   late  malformed\n";
  for (const auto& [name, c] : channels) {
    std::snprintf(line, sizeof line, "%-18s %8lld %10.1f %9.1f %7lld %6lld %9lld%s\n", name.c_str(),
                  static_cast<long long>(c.count), c.rate_hz, c.expected_hz, static_cast<long long>(c.drops),
                  static_cast<long long>(c.late), static_cast<long long>(c.malformed),
                  c.wall_clock ? "  (per wall second)" : "");
    out << line;
  }
  out << "\nloop timing " << (s.clock == "lockstep" ? "(lockstep: wall time per step / per wait)" : "(wake-up jitter)")
      << "\nprocess        rate [Hz]    loops  overruns   p50 [us]   p99 [us]   max [us]\n";
  for (const auto& [name, t] : mon.timing()) {
    std::snprintf(line, sizeof line, "%-14s %9.1f %8lld %9lld %10.1f %10.1f %10.1f\n", name.c_str(), t.loop_rate_hz,
                  static_cast<long long>(t.loop_count), static_cast<long long>(t.overruns), t.jitter_p50_us,
                  t.jitter_p99_us, t.jitter_max_us);
    out << line;
  }
  for (const auto& [name, t] : mon.timing()) {
    if (t.latency_count == 0) continue;
    const char* what = name == "plant" ? "control loop latency (TRUTH published -> ACTUATOR_CMD received)"
                       : name == "estimator" ? "latency (IMU sample time -> ESTIMATE published)"
                                             : "latency";
    std::snprintf(line, sizeof line, "%s %s: p50 %.1f us, p99 %.1f us, max %.1f us over %lld messages\n",
                  name.c_str(), what, t.latency_p50_us, t.latency_p99_us, t.latency_max_us,
                  static_cast<long long>(t.latency_count));
    out << line;
  }
  out << "\nflight     max |p| " << std::to_string(f.max_abs_p).substr(0, 6) << " rad/s, max |v| "
      << std::to_string(f.max_abs_v).substr(0, 6) << " m/s, max |phi| "
      << std::to_string(f.max_abs_phi * 180 / M_PI).substr(0, 6) << " deg";
  if (f.max_abs_theta > 0.0) out << ", max |theta| " << std::to_string(f.max_abs_theta * 180 / M_PI).substr(0, 6) << " deg";
  out << "\n";
  std::snprintf(line, sizeof line, "ranges     p %.2f rad/s, v %.2f m/s, phi %.2f rad, delta_f %.1f rad/s\n",
                f.max_p - f.min_p, f.max_v - f.min_v, f.max_phi - f.min_phi, f.max_df - f.min_df);
  out << line;
  std::snprintf(line, sizeof line, "final      p %.3f rad/s, v %.3f m/s, phi %.2f deg\n", f.final_p, f.final_v,
                f.final_phi * 180 / M_PI);
  out << line;
  const EstimatorSummary est = mon.estimator();
  if (est.samples > 0) {
    std::snprintf(line, sizeof line,
                  "estimator  phi error rms %.3f deg (max %.3f), p error rms %.4f rad/s, v error rms %.4f m/s over %lld "
                  "estimates; poses accepted %lld, rejected %lld, missing %lld\n",
                  est.phi_rms_deg, est.phi_max_deg, est.p_rms_radps, est.v_rms_mps, static_cast<long long>(est.samples),
                  static_cast<long long>(est.poses_accepted), static_cast<long long>(est.poses_rejected),
                  static_cast<long long>(est.poses_missing));
    out << line;
    if (est.poses_too_old + est.poses_too_new + est.velocity_windows_uncovered + est.imu_rejected + est.imu_gaps > 0) {
      std::snprintf(line, sizeof line,
                    "estimator  poses dropped %lld too old, %lld too new; velocity windows uncovered %lld; IMU samples "
                    "rejected %lld, gaps %lld\n",
                    static_cast<long long>(est.poses_too_old), static_cast<long long>(est.poses_too_new),
                    static_cast<long long>(est.velocity_windows_uncovered), static_cast<long long>(est.imu_rejected),
                    static_cast<long long>(est.imu_gaps));
      out << line;
    }
  }
  for (const auto& [name, h] : mon.can_health()) {
    std::snprintf(line, sizeof line,
                  "%-10s %s: %lld messages to CAN, %lld to LCM; frames sent %lld, received %lld; rejected: unknown id "
                  "%lld, wrong length %lld, bad checksum %lld, stale counter %lld, out of range %lld; error frames "
                  "%lld; ENOBUFS %lld, dropped %lld\n",
                  name.c_str(), h.interface_name.c_str(), static_cast<long long>(h.messages_to_can),
                  static_cast<long long>(h.messages_to_lcm), static_cast<long long>(h.frames_sent),
                  static_cast<long long>(h.frames_received), static_cast<long long>(h.rejected_unknown_id),
                  static_cast<long long>(h.rejected_wrong_length), static_cast<long long>(h.rejected_bad_checksum),
                  static_cast<long long>(h.rejected_stale_counter), static_cast<long long>(h.rejected_out_of_range),
                  static_cast<long long>(h.error_frames), static_cast<long long>(h.send_enobufs),
                  static_cast<long long>(h.send_dropped + h.receive_dropped));
    out << line;
    if (h.fd) {
      out << "           CAN FD: " << h.fd_frames_sent << " of the frames sent and " << h.fd_frames_received
          << " of those received were FD frames\n";
    }
    if (!h.candump_file.empty()) out << "           candump log " << h.candump_file << " (" << h.candump_lines << " frames)\n";
  }
  out << "faults     " << mon.faults().size() << "\n";
  std::size_t shown = 0;
  for (const auto& fr : mon.faults()) {
    if (++shown > 8) {
      out << "           ...\n";
      break;
    }
    std::snprintf(line, sizeof line, "           [%s t=%.3f s] ", fr.process.c_str(), fr.rig_time_s);
    out << line << fr.message << "\n";
  }
  out << "processes ";
  for (const auto& c : children) out << " " << c.name << "(" << (c.exited ? describe_exit(c) : "running") << ")";
  out << "\n";
  out << "controlled " << (controlled ? "yes" : "NO") << ", returned to hover " << (hover ? "yes" : "no") << "\n";
  out << "result     " << verdict << "\n";
}

std::string summary_json(const Scenario& s, const std::string& url, const std::string& log_file, double sim_s,
                         double wall_s, const std::map<std::string, ChannelSummary>& channels, const RunMonitor& mon,
                         const std::vector<Child>& children, bool controlled, bool hover, int exit_code,
                         const std::string& verdict) {
  const FlightSummary& f = mon.flight();
  JsonWriter w;
  w.begin_object();
  w.key("scenario").value(s.name);
  w.key("clock").value(s.clock);
  w.key("seed").value(static_cast<long long>(s.seed));
  w.key("lcm_url").value(url);
  w.key("log").value(log_file);
  w.key("controlled").value(controlled);
  w.key("returned_to_hover").value(hover);
  w.key("exit_code").value(exit_code);
  w.key("result").value(verdict);
  w.key("sim_time_s").value(sim_s);
  w.key("wall_time_s").value(wall_s);
  w.key("speed_x_realtime").value(wall_s > 0 ? sim_s / wall_s : 0.0);
  w.key("max_abs").begin_object().key("p").value(f.max_abs_p).key("v").value(f.max_abs_v).key("phi").value(f.max_abs_phi).key("theta").value(f.max_abs_theta).end_object();
  w.key("ranges").begin_object();
  w.key("p").value(f.max_p - f.min_p).key("v").value(f.max_v - f.min_v).key("phi").value(f.max_phi - f.min_phi);
  w.key("delta_f").value(f.max_df - f.min_df);
  w.end_object();
  w.key("final").begin_object().key("p").value(f.final_p).key("v").value(f.final_v).key("phi").value(f.final_phi).end_object();
  const EstimatorSummary est = mon.estimator();
  if (est.samples > 0) {
    w.key("estimator").begin_object();
    w.key("samples").value(static_cast<long long>(est.samples));
    w.key("phi_rms_deg").value(est.phi_rms_deg).key("phi_max_deg").value(est.phi_max_deg);
    w.key("p_rms_radps").value(est.p_rms_radps).key("v_rms_mps").value(est.v_rms_mps);
    w.key("poses_accepted").value(static_cast<long long>(est.poses_accepted));
    w.key("poses_rejected").value(static_cast<long long>(est.poses_rejected));
    w.key("poses_missing").value(static_cast<long long>(est.poses_missing));
    w.key("poses_too_old").value(static_cast<long long>(est.poses_too_old));
    w.key("poses_too_new").value(static_cast<long long>(est.poses_too_new));
    w.key("velocity_windows_uncovered").value(static_cast<long long>(est.velocity_windows_uncovered));
    w.key("imu_rejected").value(static_cast<long long>(est.imu_rejected));
    w.key("imu_gaps").value(static_cast<long long>(est.imu_gaps));
    w.end_object();
  }
  if (!mon.can_health().empty()) {
    w.key("can").begin_object();
    for (const auto& [name, h] : mon.can_health()) {
      const auto n = [](int64_t v) { return static_cast<long long>(v); };
      w.key(name).begin_object();
      w.key("interface").value(h.interface_name);
      w.key("messages_to_can").value(n(h.messages_to_can)).key("messages_to_lcm").value(n(h.messages_to_lcm));
      w.key("frames_sent").value(n(h.frames_sent)).key("frames_received").value(n(h.frames_received));
      w.key("fd").value(h.fd != 0);
      w.key("fd_frames_sent").value(n(h.fd_frames_sent)).key("fd_frames_received").value(n(h.fd_frames_received));
      w.key("rejected_unknown_id").value(n(h.rejected_unknown_id));
      w.key("rejected_wrong_length").value(n(h.rejected_wrong_length));
      w.key("rejected_bad_checksum").value(n(h.rejected_bad_checksum));
      w.key("rejected_stale_counter").value(n(h.rejected_stale_counter));
      w.key("rejected_out_of_range").value(n(h.rejected_out_of_range));
      w.key("counter_gaps").value(n(h.counter_gaps)).key("saturated_values").value(n(h.saturated_values));
      w.key("error_frames").value(n(h.error_frames)).key("bus_state").value(static_cast<int>(h.bus_state));
      w.key("last_error").value(h.last_error);
      w.key("send_enobufs").value(n(h.send_enobufs)).key("send_retries").value(n(h.send_retries));
      w.key("send_dropped").value(n(h.send_dropped)).key("receive_dropped").value(n(h.receive_dropped));
      w.key("candump_file").value(h.candump_file).key("candump_lines").value(n(h.candump_lines));
      w.end_object();
    }
    w.end_object();
  }
  w.key("channels").begin_object();
  for (const auto& [name, c] : channels) {
    w.key(name).begin_object();
    w.key("count").value(static_cast<long long>(c.count));
    w.key("rate_hz").value(c.rate_hz);
    w.key("expected_hz").value(c.expected_hz);
    w.key("drops").value(static_cast<long long>(c.drops));
    w.key("late").value(static_cast<long long>(c.late));
    w.key("malformed").value(static_cast<long long>(c.malformed));
    w.key("rate_basis").value(c.wall_clock ? "wall" : "sim");
    w.end_object();
  }
  w.end_object();
  w.key("timing").begin_object();
  for (const auto& [name, t] : mon.timing()) {
    w.key(name).begin_object();
    w.key("loop_rate_hz").value(t.loop_rate_hz);
    w.key("loop_count").value(static_cast<long long>(t.loop_count));
    w.key("overruns").value(static_cast<long long>(t.overruns));
    w.key("jitter_p50_us").value(t.jitter_p50_us);
    w.key("jitter_p99_us").value(t.jitter_p99_us);
    w.key("jitter_max_us").value(t.jitter_max_us);
    w.key("latency_count").value(static_cast<long long>(t.latency_count));
    w.key("latency_p50_us").value(t.latency_p50_us);
    w.key("latency_p99_us").value(t.latency_p99_us);
    w.key("latency_max_us").value(t.latency_max_us);
    w.end_object();
  }
  w.end_object();
  w.key("faults").begin_array();
  for (const auto& fr : mon.faults()) {
    w.begin_object();
    w.key("process").value(fr.process).key("severity").value(fr.severity).key("code").value(fr.code);
    w.key("channel").value(fr.channel).key("message").value(fr.message).key("rig_time_s").value(fr.rig_time_s);
    w.end_object();
  }
  w.end_array();
  w.key("processes").begin_object();
  for (const auto& c : children) {
    w.key(c.name).begin_object();
    w.key("pid").value(static_cast<long long>(c.pid));
    w.key("exit_code").value(c.exit_code);
    w.key("signal").value(c.signal);
    w.end_object();
  }
  w.end_object();
  w.end_object();
  return w.str();
}

}  // namespace

Scenario prepare_scenario(const RunOptions& options) {
  std::vector<Override> overrides = options.overrides;
  if (options.clock) {
    if (*options.clock != "realtime" && *options.clock != "lockstep") {
      throw ConfigError("--clock", "clock", *options.clock, "must be realtime or lockstep");
    }
    overrides.push_back({"clock", *options.clock});
  }
  if (options.seed) overrides.push_back({"seed", std::to_string(*options.seed)});
  Scenario s = load_scenario(options.scenario_file, overrides);
  validate_process_sections(s);
  lockstep_options(s);
  launch_config_from(s);
  judge_config_from(s);
  return s;
}

int check_host() {
  const std::string url = "udpm://239.255.76.67:7667?ttl=0";
  std::cout << "LCM multicast on this host's loopback (" << url << "): ";
  if (lcm_url_works(url)) {
    std::cout << "works\n";
    return 0;
  }
  std::cout << "does NOT work (no multicast route or loopback multicast off)\n";
  // Probe a private namespace in a child, so this process stays where it is.
  const pid_t pid = ::fork();
  if (pid == 0) {
    const NamespaceResult r = enter_private_network_namespace();
    ::_exit(r.ok && lcm_url_works(url) ? 0 : 1);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  const bool ns_ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
  std::cout << "private network namespace with multicast loopback: " << (ns_ok ? "works" : "does NOT work") << "\n";
  if (ns_ok) {
    std::cout << "'rig run' will run each rig in its own private namespace. To run LCM tools on the host\n"
                 "itself (lcm-spy on a host-level URL), fix the host's loopback with:\n"
              << multicast_fix_commands() << "\n";
    return 0;
  }
  std::cout << "Neither works. Fix the host's loopback with:\n" << multicast_fix_commands() << "\n";
  return 1;
}

int run_scenario(const RunOptions& options) {
  Scenario scenario;
  LaunchConfig lc;
  JudgeConfig jc;
  ProcessRates rates;
  try {
    scenario = prepare_scenario(options);
    lc = launch_config_from(scenario);
    jc = judge_config_from(scenario);
    rates = process_rates(scenario);
  } catch (const ConfigError& e) {
    std::cerr << "rig run: config error: " << e.what() << "\n";
    return kRunBadInput;
  }
  const bool lockstep = scenario.clock == "lockstep";

  // Transport: a private network namespace unless told otherwise (before any thread).
  std::string url = lc.lcm_url;
  std::string ns_detail;
  if (url == "auto") {
    url = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608";
    bool in_ns = false;
    if (lc.network_namespace != "never") {
      const NamespaceResult r = enter_private_network_namespace();
      in_ns = r.ok;
      ns_detail = r.ok ? r.detail : "";
      if (!r.ok && lc.network_namespace == "always") {
        std::cerr << "rig run: cannot create a private network namespace: " << r.detail << "\n";
        return kRunBadInput;
      }
    }
    if (!in_ns) {
      // Host loopback: a port of its own so that parallel runs do not hear each other.
      url = "udpm://239.255.76.67:" + std::to_string(20000 + ::getpid() % 20000) + "?ttl=0&recv_buf_size=8388608";
      ns_detail = "host network, port chosen per run";
    }
  }

  // Record of the run: log, resolved scenario, process outputs.
  std::string log_file = options.log_file;
  if (log_file.empty()) log_file = "rig_logs/" + scenario.name + "-" + timestamp() + ".lcmlog";
  std::error_code ec;
  if (fs::path(log_file).has_parent_path()) fs::create_directories(fs::path(log_file).parent_path(), ec);
  const std::string resolved_file = log_file + ".scenario.yaml";
  if (scenario.actuator_link == "can") {
    ConfigMap section = scenario.section("can_bridge");
    const can::CanBridgeConfig cc = can::can_bridge_config_from(section);
    if (cc.candump_log && cc.candump_file.empty()) {
      scenario.root["can_bridge"]["candump_file"] = fs::absolute(log_file + ".candump").string();
    }
    // The interface lives in the run's network namespace: a virtual one is made there.
    const std::string problem = ensure_can_interface(cc.interface, cc.create_virtual, cc.fd);
    if (!problem.empty()) {
      std::cerr << "rig run: actuator_link can: " << problem << "\n";
      return kRunBadInput;
    }
  }
  {
    std::ofstream out(resolved_file);
    out << "# Resolved scenario of this run (bases merged, overrides applied): " << scenario.file << "\n";
    out << to_yaml(scenario.root);
    if (!out) {
      std::cerr << "rig run: cannot write " << resolved_file << "\n";
      return kRunBadInput;
    }
  }

  std::unique_ptr<transport::Bus> bus;
  try {
    bus = std::make_unique<transport::Bus>(url);
  } catch (const transport::TransportError& e) {
    std::cerr << "rig run: " << e.what() << "\nFix:\n" << multicast_fix_commands() << "\n";
    return kRunBadInput;
  }
  lcm::LogFile log(log_file, "w");
  if (!log.good()) {
    std::cerr << "rig run: cannot open log " << log_file << " for writing\n";
    return kRunBadInput;
  }

  MonitorConfig mc;
  mc.lockstep = lockstep;
  mc.late_threshold_us = lc.late_threshold_us;
  mc.expected_hz = contract::expected_rates(
      rates, contract::RunShape{lockstep, lockstep_options(scenario).logger_period_ms, scenario.processes.size()});
  mc.wall_clock_channels = contract::wall_clock_channels();
  RunMonitor monitor(mc);
  int64_t event_number = 0;
  int64_t last_flush_ns = monotonic_ns();
  // Lockstep: the launcher's logger is a participant. It acknowledges a tick once it has
  // logged everything before it, every logger_period_ms of simulated time, so the run can
  // never outpace the log (no message lost, whatever the load).
  const std::string kLogger = "logger";
  const int64_t logger_period_ns = static_cast<int64_t>(lockstep_options(scenario).logger_period_ms * 1e6);
  int64_t logger_next_due_ns = 0, logger_ack_seq = 0;
  bus->subscribe_raw(".*", [&](const std::string& channel, const void* data, int size, int64_t recv_us) {
    if (channel == "LCM_SELF_TEST") return;  // the udpm provider's own start-up probe
    lcm::LogEvent ev;
    ev.eventnum = event_number++;
    ev.timestamp = transport::wall_us();
    ev.channel = channel;
    ev.datalen = size;
    ev.data = const_cast<void*>(data);
    log.writeEvent(&ev);
    monitor.on_message(channel, data, size, recv_us * 1000);
    if (lockstep && channel == contract::channels::kRigClock) {
      rig_clock_t tick{};
      if (tick.decode(data, 0, size) == size && tick.sim_time_ns >= logger_next_due_ns) {
        logger_next_due_ns = tick.sim_time_ns + logger_period_ns;
        step_ack_t ack{};
        ack.utime = tick.utime;
        ack.seq = logger_ack_seq++;
        ack.step = tick.step;
        ack.next_due_ns = logger_next_due_ns;
        ack.process = kLogger;
        bus->publish(contract::channels::kStepAck, ack);
      }
    }
  });

  struct sigaction sa{};
  sa.sa_handler = on_interrupt;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);

  int64_t run_control_seq = 0;

  // Start every process.
  const std::string bin_dir = options.bin_dir.empty() ? self_dir() : options.bin_dir;
  std::vector<Child> children;
  for (const auto& name : scenario.processes) {
    Child c;
    c.name = name;
    c.output_file = log_file + "." + name + ".out";
    const std::string exe = bin_dir + "/" + executable_of(name);
    c.pid = spawn(exe, {"--name", name, "--scenario", resolved_file, "--lcm-url", url}, c.output_file, lc.rig_cpus);
    children.push_back(c);
  }
  if (const std::string note = pin_to(lc.rig_cpus); !note.empty()) std::cerr << "rig run: run.rig_cpus: " << note << "\n";
  if (const std::string note = pin_to(lc.launcher_cpus); !note.empty()) {
    std::cerr << "rig run: run.launcher_cpus: " << note << "\n";
  }
  // Real time: the launcher only records and watches, so it yields the CPU to the rig's
  // processes. (In lockstep it paces the run through its acknowledgements instead.)
  if (!lockstep) ::setpriority(PRIO_PROCESS, 0, 10);

  const auto stop_all = [&](double grace_s) {
    run_control_t stop;
    stop.utime = transport::wall_us();
    stop.seq = run_control_seq++;
    stop.command = run_control_t::COMMAND_STOP;
    stop.clock_mode = lockstep ? run_control_t::CLOCK_MODE_LOCKSTEP : run_control_t::CLOCK_MODE_REALTIME;
    stop.run_id = scenario.name;
    stop.num_participants = 0;
    bus->publish(contract::channels::kRunControl, stop);
    const auto wait_exit = [&](double seconds) {
      const int64_t until = monotonic_ns() + static_cast<int64_t>(seconds * 1e9);
      while (monotonic_ns() < until) {
        reap(children);
        bool all = true;
        for (const auto& c : children) all = all && c.exited;
        if (all) return true;
        bus->handle_timeout(10);
      }
      return false;
    };
    if (wait_exit(grace_s)) return;
    for (const auto& c : children) {
      if (!c.exited) ::kill(c.pid, SIGTERM);
    }
    if (wait_exit(1.0)) return;
    for (const auto& c : children) {
      if (!c.exited) ::kill(c.pid, SIGKILL);
    }
    wait_exit(1.0);
  };
  const auto fail = [&](const std::string& message) {
    std::cerr << "rig run: " << message << "\n";
    stop_all(0.5);
    bus->drain();
    std::fflush(log.getFilePtr());
    return kRunFailed;
  };

  // Wait for READY from every process.
  const int64_t ready_deadline = monotonic_ns() + static_cast<int64_t>(lc.ready_timeout_s * 1e9);
  for (;;) {
    bus->handle_timeout(10);
    if (Child* dead = reap(children)) {
      return fail("process '" + dead->name + "' " + describe_exit(*dead) + " before it was ready:\n" +
                  tail_of(dead->output_file, 12));
    }
    bool all_ready = true;
    std::string waiting;
    for (const auto& c : children) {
      if (monitor.heartbeat_state(c.name) != heartbeat_t::STATE_READY) {
        all_ready = false;
        waiting += (waiting.empty() ? "" : ", ") + c.name;
      }
    }
    if (all_ready) break;
    if (g_interrupted) return fail("interrupted while waiting for processes to be ready");
    if (monotonic_ns() > ready_deadline) {
      return fail("timed out after " + std::to_string(lc.ready_timeout_s) +
                  " s waiting for HEARTBEAT READY from: " + waiting);
    }
  }

  // Start the run.
  run_control_t start;
  start.utime = transport::wall_us();
  start.seq = run_control_seq++;
  start.command = run_control_t::COMMAND_START;
  start.clock_mode = lockstep ? run_control_t::CLOCK_MODE_LOCKSTEP : run_control_t::CLOCK_MODE_REALTIME;
  const int64_t wall_start_ns = monotonic_ns();
  start.t0_monotonic_ns = lockstep ? 0 : wall_start_ns + static_cast<int64_t>(lc.start_delay_s * 1e9);
  start.duration_ns = static_cast<int64_t>(std::llround(scenario.duration_s * 1e9));
  start.run_id = scenario.name + "-" + std::to_string(::getpid());
  for (const auto& p : scenario.processes) {
    if (p != "plant") start.participants.push_back(p);
  }
  if (lockstep) start.participants.push_back(kLogger);
  start.num_participants = static_cast<int32_t>(start.participants.size());
  bus->publish(contract::channels::kRunControl, start);
  monitor.set_t0(start.t0_monotonic_ns);
  const int64_t t0 = lockstep ? wall_start_ns : start.t0_monotonic_ns;

  // Monitor until the run is complete, fails or is interrupted.
  std::string failure;
  bool interrupted = false;
  int64_t next_progress_ns = wall_start_ns;
  int64_t last_progress_truth = -1, last_progress_change_ns = wall_start_ns;
  const bool tty = ::isatty(STDERR_FILENO);
  int resends = 0;
  for (;;) {
    bus->handle_timeout(5);
    const int64_t now = monotonic_ns();
    if (now - last_flush_ns > 100000000LL) {
      std::fflush(log.getFilePtr());
      last_flush_ns = now;
    }
    if (Child* dead = reap(children)) {
      bus->drain();
      std::string why;
      for (auto it = monitor.faults().rbegin(); it != monitor.faults().rend(); ++it) {
        if (it->process == dead->name && it->severity >= 3) {
          why = "\n  its last fatal fault: " + it->message;
          break;
        }
      }
      failure = "process '" + dead->name + "' (pid " + std::to_string(dead->pid) + ") " + describe_exit(*dead) +
                " during the run at simulated t = " + std::to_string(monitor.sim_time_s()) + " s" + why +
                "\n  last output (" + dead->output_file + "):\n" + tail_of(dead->output_file, 8);
      break;
    }
    if (g_interrupted) {
      interrupted = true;
      break;
    }
    // Processes that missed the start command get it again.
    if (resends < 5 && now - wall_start_ns > (resends + 1) * 300000000LL) {
      bool someone_waiting = false;
      for (const auto& c : children) someone_waiting |= monitor.heartbeat_state(c.name) == heartbeat_t::STATE_READY;
      if (someone_waiting) {
        start.seq = run_control_seq++;
        bus->publish(contract::channels::kRunControl, start);
      }
      ++resends;
    }
    bool done = false;
    if (lockstep) {
      done = monitor.heartbeat_state("plant") == heartbeat_t::STATE_FINISHED;
      if (monitor.truth_count() != last_progress_truth) {
        last_progress_truth = monitor.truth_count();
        last_progress_change_ns = now;
      } else if (now - last_progress_change_ns > static_cast<int64_t>(lc.stall_timeout_s * 1e9)) {
        failure = "lockstep run stalled: no new TRUTH for " + std::to_string(lc.stall_timeout_s) + " s at t = " +
                  std::to_string(monitor.sim_time_s()) + " s";
        break;
      }
    } else {
      done = now >= t0 + start.duration_ns + 20000000LL;
    }
    if (done) break;
    if (options.progress && now >= next_progress_ns) {
      const double wall = static_cast<double>(now - wall_start_ns) / 1e9;
      char buf[200];
      std::snprintf(buf, sizeof buf, "[%s] sim %7.2f / %.2f s   wall %7.2f s   %6.1fx   TRUTH %lld   faults %zu",
                    scenario.clock.c_str(), monitor.sim_time_s(), scenario.duration_s, wall,
                    wall > 0 ? monitor.sim_time_s() / wall : 0.0, static_cast<long long>(monitor.truth_count()),
                    monitor.faults().size());
      if (tty) std::fprintf(stderr, "\r%s", buf);
      else std::fprintf(stderr, "%s\n", buf);
      next_progress_ns = now + (tty ? 200000000LL : 2000000000LL);
    }
  }
  const double wall_s = static_cast<double>(monotonic_ns() - wall_start_ns) / 1e9;
  if (options.progress && tty) std::fprintf(stderr, "\n");
  stop_all(failure.empty() ? lc.stop_grace_s : 0.5);
  bus->drain();
  std::fflush(log.getFilePtr());

  // Judge and report.
  const FlightSummary& f = monitor.flight();
  const double sim_s = monitor.sim_time_s();
  const bool controlled = f.samples > 0 && f.finite && f.max_abs_phi <= jc.max_phi_deg * M_PI / 180.0 &&
                          f.max_abs_theta <= jc.max_theta_deg * M_PI / 180.0;
  const bool hover = controlled && std::fabs(f.final_phi) <= jc.hover_phi_deg * M_PI / 180.0 &&
                     std::fabs(f.final_p) <= jc.hover_p_radps && std::fabs(f.final_v) <= jc.hover_v_mps;
  int code = kRunOk;
  std::string verdict = "ok";
  if (interrupted) {
    code = kRunInterrupted;
    verdict = "interrupted";
  } else if (!failure.empty()) {
    code = kRunFailed;
    verdict = "failed: " + failure.substr(0, failure.find('\n'));
    std::cerr << "rig run: " << failure << "\n";
  } else if (!controlled) {
    code = kRunNotControlled;
    verdict = "completed, vehicle NOT controlled";
  }
  const auto channels = monitor.channels(sim_s, wall_s);
  print_summary(std::cout, scenario, url, ns_detail, log_file, sim_s, wall_s, channels, monitor, children, controlled,
                hover, verdict);
  if (!options.json_file.empty()) {
    std::ofstream out(options.json_file);
    out << summary_json(scenario, url, log_file, sim_s, wall_s, channels, monitor, children, controlled, hover, code,
                        verdict)
        << "\n";
    if (!out) std::cerr << "rig run: cannot write " << options.json_file << "\n";
  }
  return code;
}

}  // namespace nimble::launcher
