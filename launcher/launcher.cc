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
#include <cerrno>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>

#include <lcm/lcm-cpp.hpp>
#include <nimble/fault_event_t.hpp>
#include <nimble/heartbeat_t.hpp>
#include <nimble/rig_clock_t.hpp>
#include <nimble/run_control_t.hpp>
#include <nimble/step_ack_t.hpp>

#include "can_bridge/bridge_config.h"
#include "contract/channels.h"
#include "contract/decode.h"
#include "contract/rates.h"
#include "core/json_writer.h"
#include "launcher/hosts.h"
#include "launcher/inprocess.h"
#include "launcher/netns.h"
#include "launcher/recorder.h"
#include "launcher/run_monitor.h"
#include "launcher/run_report.h"
#include "launcher/scenario_check.h"
#include "launcher/supervisor.h"
#include "launcher/verdict.h"
#include "transport/bus.h"
#include "transport/clock.h"

namespace nimble::launcher {

std::string writable_problem(const std::string& file) {
  const bool existed = std::filesystem::exists(file);
  errno = 0;
  {
    std::ofstream out(file, std::ios::app);
    if (!out) return std::string("cannot be written (") + (errno ? std::strerror(errno) : "open failed") + ")";
  }
  if (!existed) std::filesystem::remove(file);
  return "";
}

namespace {

namespace fs = std::filesystem;
using transport::monotonic_ns;

volatile std::sig_atomic_t g_interrupted = 0;
extern "C" void on_interrupt(int) { g_interrupted = 1; }

std::string self_dir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string(".") : exe.parent_path().string();
}

/// The executable of a rig process: nimble_<name>; both sides of the CAN bridge run
/// nimble_can_bridge (their name selects the side).
std::string executable_of(const std::string& process) {
  if (process == can::kFlightProcess || process == can::kRigProcess) return "nimble_can_bridge";
  return "nimble_" + process;
}

/// Flies `plan` with each rig process its own OS process over LCM (clock realtime or lockstep).
int run_processes(RunPlan& plan, const RunOptions& options);

}  // namespace

int check_host(const std::string& json_target) {
  // With --json -, stdout carries the JSON and the text goes to stderr.
  std::ostream& out = json_target == "-" ? std::cerr : std::cout;
  const std::string url = "udpm://239.255.76.67:7667?ttl=0";
  out << "LCM multicast on this host's loopback (" << url << "): ";
  const bool host_ok = lcm_url_works(url);
  bool ns_ok = false;
  if (host_ok) {
    out << "works\n";
  } else {
    out << "does NOT work (no multicast route or loopback multicast off)\n";
    // Probe a private namespace in a child, so this process stays where it is.
    const pid_t pid = ::fork();
    if (pid == 0) {
      const NamespaceResult r = enter_private_network_namespace();
      ::_exit(r.ok && lcm_url_works(url) ? 0 : 1);
    }
    int status = 0;
    ::waitpid(pid, &status, 0);
    ns_ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
    out << "private network namespace with multicast loopback: " << (ns_ok ? "works" : "does NOT work") << "\n";
    if (ns_ok) {
      out << "'rig run' will run each rig in its own private namespace. To run LCM tools on the host\n"
             "itself (lcm-spy on a host-level URL), fix the host's loopback with:\n"
          << multicast_fix_commands() << "\n";
    } else {
      out << "Neither works. Fix the host's loopback with:\n" << multicast_fix_commands() << "\n";
    }
  }
  const bool ok = host_ok || ns_ok;
  if (!json_target.empty()) {
    JsonWriter w;
    w.begin_object();
    w.key("url").value(url).key("host_multicast").value(host_ok);
    w.key("private_namespace").value(host_ok ? "not needed" : (ns_ok ? "works" : "does not work"));
    w.key("runs_can_start").value(ok);
    if (!host_ok) w.key("fix").value(multicast_fix_commands());
    w.end_object();
    if (json_target == "-") {
      std::cout << w.str() << "\n";
    } else {
      std::ofstream f(json_target);
      f << w.str() << "\n";
      if (!f) {
        std::cerr << "rig check: cannot write " << json_target << "\n";
        return kRunBadInput;
      }
    }
  }
  return ok ? 0 : 1;
}

int run_scenario(const RunOptions& options) {
  RunPlan plan;
  try {
    plan = load_run_plan(options);
  } catch (const ConfigError& e) {
    std::cerr << "rig run: config error: " << e.what() << "\n";
    return kRunBadInput;
  }
  // An output that cannot be written is found now, not after the flight.
  if (!options.json_file.empty() && options.json_file != "-") {
    if (const std::string problem = writable_problem(options.json_file); !problem.empty()) {
      std::cerr << "rig run: --json " << options.json_file << ": " << problem << "\n";
      return kRunBadInput;
    }
  }
  if (plan.inprocess()) return run_inprocess(plan, options);
  return run_processes(plan, options);
}

namespace {

int run_processes(RunPlan& plan, const RunOptions& options) {
  Scenario& scenario = plan.scenario;
  const LaunchConfig& lc = plan.launch;
  const bool lockstep = scenario.clock == kClockLockstep;

  // Transport: a private network namespace unless told otherwise (before any thread).
  std::string url = lc.lcm_url;
  std::string ns_detail;
  bool in_ns = false;
  if (url == "auto") {
    url = kNamespaceLcmUrl;
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
  // Two emulated hosts: the second is a network namespace of its own behind a veth pair (hosts.h).
  std::unique_ptr<HostLink> host_link;
  if (plan.hosts.emulated()) {
    std::string problem;
    host_link = link_hosts(plan.hosts, in_ns, &problem);
    if (!host_link) {
      std::cerr << "rig run: hosts: " << problem << "\n";
      return kRunBadInput;
    }
    url = kTwoHostLcmUrl;
    ns_detail += "; to host '" + plan.hosts.hosts[1].name + "': " + host_link->detail();
  }
  std::cerr << "rig run: pid " << ::getpid() << " (watch live: "
            << (in_ns ? "rig spy --pid " + std::to_string(::getpid()) : "rig spy --url '" + url + "'") << ")\n";

  // Record of the run: log, resolved scenario, process outputs.
  const std::string log_file = log_file_for(plan, options);
  std::error_code ec;
  if (fs::path(log_file).has_parent_path()) fs::create_directories(fs::path(log_file).parent_path(), ec);
  place_candump_log(plan, log_file);
  if (scenario.actuator_link == "can") {
    ConfigMap section = scenario.section("can_bridge");
    const can::CanBridgeConfig cc = can::can_bridge_config_from(section);
    // The interface lives in the run's network namespace: a virtual one is made there.
    const std::string problem = ensure_can_interface(cc.interface, cc.create_virtual, cc.fd);
    if (!problem.empty()) {
      std::cerr << "rig run: actuator_link can: " << problem << "\n";
      return kRunBadInput;
    }
  }
  std::string resolved_file;
  // The run's configuration as the processes will load it: the resolved scenario and the files it
  // names, read now. A process that reads another (a file changed since) is refused.
  std::string run_digest;
  try {
    resolved_file = write_resolved_scenario(plan, log_file);
    run_digest = scenario_digest(load_scenario(resolved_file));
  } catch (const std::exception& e) {
    std::cerr << "rig run: " << e.what() << "\n";
    return kRunBadInput;
  }

  std::unique_ptr<transport::Bus> bus;
  try {
    bus = std::make_unique<transport::Bus>(url);
  } catch (const transport::TransportError& e) {
    std::cerr << "rig run: " << e.what() << "\nFix:\n" << multicast_fix_commands() << "\n";
    return kRunBadInput;
  }
  RunMonitor monitor(monitor_config(plan));
  std::unique_ptr<Recorder> recorder;
  try {
    recorder = std::make_unique<Recorder>(log_file, monitor, lockstep ? LogStamps::kSimulated : LogStamps::kWallClock);
  } catch (const std::exception& e) {
    std::cerr << "rig run: " << e.what() << "\n";
    return kRunBadInput;
  }
  // Lockstep: the launcher's logger is a participant. It acknowledges a tick once it has
  // logged everything before it, every logger_period_ms of simulated time, so the run can
  // never outpace the log (no message lost, whatever the load).
  const std::string kLogger = "logger";
  const int64_t logger_period_ns = static_cast<int64_t>(plan.logger_period_ms * 1e6);
  int64_t logger_next_due_ns = 0, logger_ack_seq = 0;
  bus->subscribe_raw(".*", [&](const std::string& channel, const void* data, int size, int64_t recv_us) {
    if (channel == "LCM_SELF_TEST") return;  // the udpm provider's own start-up probe
    recorder->record(channel, data, size, recv_us * 1000);
    if (lockstep && channel == contract::channels::kRigClock) {
      rig_clock_t tick{};
      if (contract::decode_exact(data, size, tick) && tick.sim_time_ns >= logger_next_due_ns) {
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
  int64_t launcher_fault_seq = 0;

  // Start every process.
  const std::string bin_dir = options.bin_dir.empty() ? self_dir() : options.bin_dir;
  ProcessSupervisor supervisor;
  const auto external = [&](const std::string& name) {
    return std::find(lc.external_processes.begin(), lc.external_processes.end(), name) != lc.external_processes.end();
  };
  for (const auto& name : scenario.processes) {
    if (external(name)) {
      std::cerr << "rig run: " << name << " is external: start it in this run's network"
                << (ns_detail.empty() || url != kNamespaceLcmUrl ? "" : " (nsenter -t " + std::to_string(::getpid()) + " -n)")
                << " with\n  " << bin_dir << "/" << executable_of(name) << " --name " << name << " --scenario "
                << resolved_file << " --lcm-url '" << url << "'\n";
      continue;
    }
    const int host_ns = host_link && plan.hosts.host_index(name) > 0 ? host_link->remote_namespace_fd() : -1;
    supervisor.start(name, bin_dir + "/" + executable_of(name),
                     {"--name", name, "--scenario", resolved_file, "--lcm-url", url}, log_file + "." + name + ".out",
                     lc.rig_cpus, host_ns);
  }
  const std::vector<ChildProcess>& children = supervisor.children();
  if (const std::string note = pin_to(lc.rig_cpus); !note.empty()) std::cerr << "rig run: run.rig_cpus: " << note << "\n";
  if (const std::string note = pin_to(lc.launcher_cpus); !note.empty()) {
    std::cerr << "rig run: run.launcher_cpus: " << note << "\n";
  }
  // Real time: the launcher only records and watches, so it yields the CPU to the rig's
  // processes. (In lockstep it paces the run through its acknowledgements instead.)
  if (!lockstep) ::setpriority(PRIO_PROCESS, 0, 10);

  const auto stop_all = [&](double grace_s) {
    const auto ask = [&] {
      run_control_t stop;
      stop.utime = transport::wall_us();
      stop.seq = run_control_seq++;
      stop.command = run_control_t::COMMAND_STOP;
      stop.clock_mode = lockstep ? run_control_t::CLOCK_MODE_LOCKSTEP : run_control_t::CLOCK_MODE_REALTIME;
      stop.run_id = scenario.name;
      stop.num_participants = 0;
      bus->publish(contract::channels::kRunControl, stop);
    };
    supervisor.stop(grace_s, ask, [&] { bus->handle_timeout(10); });
  };
  const auto fail = [&](const std::string& message, int code = kRunFailed) {
    std::cerr << "rig run: " << message << "\n";
    stop_all(0.5);
    bus->drain();
    recorder->flush();
    return code;
  };
  // Every process must fly the run's configuration: a heartbeat with another digest is a process
  // started with another scenario, or after a file the scenario names (model, manoeuvre,
  // vehicle) changed. Returns what is wrong, or "".
  const auto digest_problem = [&]() -> std::string {
    for (const auto& name : scenario.processes) {
      const RunMonitor::Heartbeat* hb = monitor.heartbeat(name);
      if (hb == nullptr || hb->digest == run_digest) continue;
      return "process '" + name + "' (pid " + std::to_string(hb->pid) + ") was started with another scenario: " +
             "configuration digest " + (hb->digest.empty() ? std::string("(none)") : hb->digest) + ", the run's " +
             run_digest + " (the scenario " + resolved_file +
             " and the files it names, as they were when the run started); refused. Start it with --scenario " +
             resolved_file + ", and change no model, manoeuvre or vehicle file during a run";
    }
    return "";
  };
  // A running process that has gone silent without exiting (stopped, hung). Returns what, or "".
  const auto heartbeat_lost = [&](int64_t now) -> std::string {
    const int64_t limit = static_cast<int64_t>(lc.heartbeat_timeout_s * 1e9);
    for (const auto& name : scenario.processes) {
      const RunMonitor::Heartbeat* hb = monitor.heartbeat(name);
      if (hb == nullptr || now - hb->recv_ns <= limit) continue;
      if (hb->state == heartbeat_t::STATE_STOPPING || hb->state == heartbeat_t::STATE_FAULT) continue;
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.1f s", 1e-9 * static_cast<double>(now - hb->recv_ns));
      const std::string what = "process '" + name + "' (pid " + std::to_string(hb->pid) + ") sent no heartbeat for " +
                               buf + " (run.heartbeat_timeout_s " + std::to_string(lc.heartbeat_timeout_s) +
                               ") and has not exited: stopped or hung";
      fault_event_t f;
      f.utime = transport::wall_us();
      f.seq = launcher_fault_seq++;
      f.rig_utime = static_cast<int64_t>(monitor.sim_time_s() * 1e6);
      f.process = "launcher";
      f.severity = fault_event_t::SEVERITY_FATAL;
      f.code = fault_event_t::CODE_HEARTBEAT_LOST;
      f.channel = contract::channels::kHeartbeat;
      f.message = what;
      bus->publish(contract::channels::kFault, f);
      return "HEARTBEAT_LOST: " + what;
    }
    return "";
  };

  // Wait for READY from every process.
  const int64_t ready_deadline = monotonic_ns() + static_cast<int64_t>(lc.ready_timeout_s * 1e9);
  for (;;) {
    bus->handle_timeout(10);
    if (const ChildProcess* dead = supervisor.reap()) {
      return fail("process '" + dead->name + "' " + dead->describe() + " before it was ready:\n" +
                  tail_of(dead->output_file, 12));
    }
    if (const std::string problem = digest_problem(); !problem.empty()) return fail(problem, kRunBadInput);
    bool all_ready = true;
    std::string waiting;
    for (const auto& name : scenario.processes) {
      if (monitor.heartbeat_state(name) != heartbeat_t::STATE_READY) {
        all_ready = false;
        waiting += (waiting.empty() ? "" : ", ") + name;
      }
    }
    if (all_ready && monitor.heartbeat("plant") != nullptr) {
      // The digests of every READY heartbeat are in: the last check before the start.
      if (const std::string problem = digest_problem(); !problem.empty()) return fail(problem, kRunBadInput);
      break;
    }
    if (g_interrupted) return fail("interrupted while waiting for processes to be ready");
    if (monotonic_ns() > ready_deadline) {
      return fail("timed out after " + std::to_string(lc.ready_timeout_s) +
                  " s waiting for HEARTBEAT READY from: " + waiting + hosts_hint(plan.hosts, waiting));
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
    recorder->flush_if_due(now);
    if (const ChildProcess* dead = supervisor.reap()) {
      bus->drain();
      std::string why;
      for (auto it = monitor.faults().rbegin(); it != monitor.faults().rend(); ++it) {
        if (it->process == dead->name && it->severity >= 3) {
          why = "\n  its last fatal fault: " + it->message;
          break;
        }
      }
      failure = "process '" + dead->name + "' (pid " + std::to_string(dead->pid) + ") " + dead->describe() +
                " during the run at simulated t = " + std::to_string(monitor.sim_time_s()) + " s" + why +
                "\n  last output (" + dead->output_file + "):\n" + tail_of(dead->output_file, 8);
      break;
    }
    if (g_interrupted) {
      interrupted = true;
      break;
    }
    if (failure = digest_problem(); !failure.empty()) break;
    if (failure = heartbeat_lost(now); !failure.empty()) break;
    // Processes that missed the start command get it again.
    if (resends < 5 && now - wall_start_ns > (resends + 1) * 300000000LL) {
      bool someone_waiting = false;
      for (const auto& name : scenario.processes) someone_waiting |= monitor.heartbeat_state(name) == heartbeat_t::STATE_READY;
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
  recorder->flush();

  // Judge and report.
  RunReport report;
  report.scenario = scenario.name;
  report.clock = scenario.clock;
  report.seed = scenario.seed;
  report.config_digest = run_digest;
  report.transport = url;
  report.transport_detail = ns_detail;
  report.log_file = log_file;
  fill_from_monitor(report, monitor, monitor.sim_time_s(), wall_s);
  for (const auto& c : children) {
    report.processes.push_back(ProcessOutcome{c.name, c.pid, c.exited, c.exit_code, c.signal, c.describe()});
  }
  for (const auto& name : lc.external_processes) {
    const RunMonitor::Heartbeat* hb = monitor.heartbeat(name);
    const bool stopped = hb != nullptr && hb->state == heartbeat_t::STATE_STOPPING;
    report.processes.push_back(ProcessOutcome{name, hb != nullptr ? hb->pid : -1, stopped, stopped ? 0 : -1, 0,
                                              hb == nullptr ? "external, never heard"
                                                            : stopped ? "external, stopped" : "external, still running"});
  }
  report.hosts = host_summaries(plan.hosts, host_link.get());
  report.verdict = judge_run(report.flight, plan.judge, interrupted, failure,
                             judge_timing(report.timing, plan.judge, !lockstep), options.strict_timing,
                             failsafe_of(monitor));
  if (!failure.empty()) std::cerr << "rig run: " << failure << "\n";
  return finish_report(report, options);
}

}  // namespace
}  // namespace nimble::launcher
