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
#include <cstdlib>
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
#include "contract/messages.h"
#include "contract/rates.h"
#include "core/json_line.h"
#include "core/output_file.h"
#include "core/output_lock.h"
#include "launcher/hosts.h"
#include "launcher/inprocess.h"
#include "launcher/lockstep_logger.h"
#include "launcher/netns.h"
#include "launcher/recorder.h"
#include "launcher/run_monitor.h"
#include "launcher/run_report.h"
#include "launcher/scenario_check.h"
#include "launcher/supervisor.h"
#include "launcher/verdict.h"
#include "transport/bus.h"
#include "transport/clock.h"
#include "transport/channel_filter.h"
#include "transport/multicast_tap.h"

namespace nimble::launcher {

namespace {

namespace fs = std::filesystem;
using transport::monotonic_ns;

volatile std::sig_atomic_t g_launch_interrupted = 0;
extern "C" void on_interrupt(int) { g_launch_interrupted = 1; }

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

/// Where the rig's Python module (nimble_rig) lies for the executables in `bin_dir`: the build
/// tree's python/ beside bin/, or the installed lib/python3/dist-packages; "" if neither has it
/// (the interpreter's own path then has to).
std::string python_module_dir(const std::string& bin_dir) {
  for (const char* rel : {"../python", "../lib/python3/dist-packages"}) {
    const std::filesystem::path dir = (std::filesystem::path(bin_dir) / rel).lexically_normal();
    std::error_code ec;
    if (std::filesystem::exists(dir / "nimble_rig" / "node.py", ec)) return dir.string();
  }
  return "";
}

/// Flies `plan` with each rig process its own OS process over LCM (clock realtime or lockstep).
int run_processes(RunPlan& plan, const RunOptions& options);

}  // namespace

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
  // The log's name is decided once (a default one carries the time), then checked and flown.
  RunOptions resolved = options;
  resolved.log_file = log_file_for(plan, options);
  // A log that will not fit is refused now, not found cut after the flight.
  if (options.space_check || options.log_max_bytes > 0) {
    const std::string problem = log_space_problem(plan, resolved.log_file, options.log_max_bytes, options.space_check);
    if (!problem.empty()) {
      std::cerr << "rig run: refused: " << problem << "\n";
      return kRunBadInput;
    }
  }
  // One writer per log: the log is taken before anything of the run is written (the resolved
  // scenario, the candump log, the processes' output files beside it), and held to the end.
  OutputLock log_lock;
  try {
    log_lock = OutputLock::file(resolved.log_file, "the log");
  } catch (const OutputError& e) {
    std::cerr << "rig run: refused: " << e.what() << "\n";
    return kRunBadInput;
  }
  if (plan.inprocess()) return run_inprocess(plan, resolved);
  return run_processes(plan, resolved);
}

namespace {

/// One run of the rig's processes over LCM, from the transport to the report. run() takes it
/// through its stages; each stage returns an exit code when the run ends there.
class ProcessRun {
 public:
  ProcessRun(RunPlan& plan, const RunOptions& options)
      : plan_(plan),
        options_(options),
        scenario_(plan.scenario),
        lc_(plan.launch),
        lockstep_(plan.scenario.clock == kClockLockstep),
        monitor_(monitor_config(plan)) {}

  int run() {
    if (const int code = open_transport(); code != kRunOk) return code;
    std::cerr << "rig run: pid " << ::getpid() << " (watch live: "
              << (in_ns_ ? "rig spy --pid " + std::to_string(::getpid()) : "rig spy --url '" + url_ + "'") << ")\n";
    if (const int code = open_record(); code != kRunOk) return code;
    // In the run's network namespace now: a follower of the run may start its threads.
    if (options_.tap.start) options_.tap.start();
    struct sigaction sa {};
    sa.sa_handler = on_interrupt;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
    start_processes();
    if (const int code = wait_ready(); code != kRunOk) return code;
    const run_control_t start = start_run();
    bool interrupted = false;
    std::string failure = watch(start, interrupted);
    const double wall_s = static_cast<double>(monotonic_ns() - wall_start_ns_) / 1e9;
    if (options_.progress && ::isatty(STDERR_FILENO)) std::fprintf(stderr, "\n");
    stop_all(failure.empty() ? lc_.stop_grace_s : 0.5);
    receive_now();
    recorder_->close();
    // A log that lost messages is the run's failure, whatever else ended it.
    if (recorder_->failed()) {
      failure = recorder_->kept().failure;
      interrupted = false;
    }
    return report(failure, interrupted, wall_s);
  }

 private:
  /// The transport: a private network namespace unless told otherwise (before any thread), and
  /// the second emulated host's link.
  int open_transport() {
    url_ = lc_.lcm_url;
    if (url_ == "auto") {
      url_ = kNamespaceLcmUrl;
      if (lc_.network_namespace != "never") {
        const NamespaceResult r = enter_private_network_namespace();
        in_ns_ = r.ok;
        ns_detail_ = r.ok ? r.detail : "";
        if (!r.ok && lc_.network_namespace == "always") {
          std::cerr << "rig run: cannot create a private network namespace: " << r.detail << "\n";
          return kRunBadInput;
        }
      }
      if (!in_ns_) {
        // Host loopback: a port of its own so that parallel runs do not hear each other.
        url_ = "udpm://239.255.76.67:" + std::to_string(20000 + ::getpid() % 20000) + "?ttl=0&recv_buf_size=8388608";
        ns_detail_ = "host network, port chosen per run";
      }
    }
    // Two emulated hosts: the second is a network namespace of its own behind a veth pair (hosts.h).
    if (plan_.hosts.emulated()) {
      std::string problem;
      host_link_ = link_hosts(plan_.hosts, in_ns_, &problem);
      if (!host_link_) {
        std::cerr << "rig run: hosts: " << problem << "\n";
        return kRunBadInput;
      }
      url_ = kTwoHostLcmUrl;
      ns_detail_ += "; to host '" + plan_.hosts.hosts[1].name + "': " + host_link_->detail();
    }
    return kRunOk;
  }

  /// The record of the run: the log, the resolved scenario and the run's digest, the bus, the
  /// monitor and the recorder (in lockstep the logger is a participant).
  int open_record() {
    log_file_ = log_file_for(plan_, options_);
    std::error_code ec;
    if (fs::path(log_file_).has_parent_path()) fs::create_directories(fs::path(log_file_).parent_path(), ec);
    place_candump_log(plan_, log_file_);
    if (scenario_.actuator_link == "can") {
      ConfigMap section = scenario_.section("can_bridge");
      const can::CanBridgeConfig cc = can::can_bridge_config_from(section);
      // The interface lives in the run's network namespace: a virtual one is made there.
      const std::string problem = ensure_can_interface(cc.interface, cc.create_virtual, cc.fd);
      if (!problem.empty()) {
        std::cerr << "rig run: actuator_link can: " << problem << "\n";
        return kRunBadInput;
      }
    }
    // The run's configuration as the processes will load it: the resolved scenario and the files it
    // names, read now. A process that reads another (a file changed since) is refused.
    try {
      resolved_file_ = write_resolved_scenario(plan_, log_file_);
      run_digest_ = scenario_digest(load_scenario(resolved_file_));
    } catch (const std::exception& e) {
      std::cerr << "rig run: " << e.what() << "\n";
      return kRunBadInput;
    }

    try {
      bus_ = std::make_unique<transport::Bus>(url_);
    } catch (const transport::TransportError& e) {
      std::cerr << "rig run: " << e.what() << "\nFix:\n" << multicast_fix_commands() << "\n";
      return kRunBadInput;
    }
    try {
      recorder_ =
          std::make_unique<Recorder>(log_file_, monitor_, lockstep_ ? LogStamps::kSimulated : LogStamps::kWallClock);
      recorder_->set_max_bytes(options_.log_max_bytes);
    } catch (const std::exception& e) {
      std::cerr << "rig run: " << e.what() << "\n";
      return kRunBadInput;
    }
    // Lockstep: the launcher's log is a participant (launcher/lockstep_logger.h).
    logger_ = std::make_unique<LockstepLogger>(
        static_cast<int64_t>(plan_.logger_period_ms * 1e6),
        [this](const step_ack_t& ack) { bus_->publish(contract::channels::kStepAck, ack); });
    auto on_message = [this](const std::string& channel, const void* data, int size, int64_t recv_us) {
      if (channel == "LCM_SELF_TEST") return;  // the udpm provider's own start-up probe
      recorder_->record(channel, data, size, recv_us * 1000);
      if (options_.tap.message) options_.tap.message(channel, data, size);
      if (lockstep_) logger_->on_message(channel, data, size);
    };
    // Over udpm the launcher reads the group itself (transport/multicast_tap.h), without
    // LCM's receive thread; its LCM instance only publishes.
    if (transport::udpm_port(url_) > 0) {
      try {
        tap_ = std::make_unique<transport::MulticastTap>(url_, on_message);
      } catch (const transport::TransportError& e) {
        std::cerr << "rig run: " << e.what() << "\nFix:\n" << multicast_fix_commands() << "\n";
        return kRunBadInput;
      }
      // LCM's own check that a receiver hears the group, as its receive thread makes it.
      const std::string probe = "rig launcher self test";
      if (!tap_->self_test([&] { bus_->publish_bytes("LCM_SELF_TEST", probe.data(), static_cast<int>(probe.size())); },
                           10000000000LL)) {
        std::cerr << "rig run: the launcher hears nothing on '" << url_
                  << "' within 10 s: multicast does not loop back\nFix:\n"
                  << multicast_fix_commands() << "\n";
        return kRunBadInput;
      }
      // The socket's buffer is all that holds the run's messages while the launcher writes its
      // log: below 2 MB (a process without CAP_NET_ADMIN gets net.core.rmem_max), say so.
      if (const int bytes = tap_->receive_buffer_bytes(); bytes < 2 * 1024 * 1024) {
        std::cerr << "rig run: warning: the launcher's receive buffer is " << bytes / 1024
                  << " kB (net.core.rmem_max); a stall of the launcher longer than it holds loses messages from "
                     "the log. Raise it: sysctl -w net.core.rmem_max=8388608\n";
      }
    } else {
      bus_->subscribe_raw(".*", on_message);
    }
    return kRunOk;
  }

  /// Receives what the run sends for up to `ms`: in lockstep waiting on the socket (the logger
  /// answers ticks), in real time without (no publish wakes the launcher).
  void receive_for(int ms) {
    if (tap_ && lockstep_ && !logger_->may_be_due_next()) {
      // No tick to answer next: read what came every 150 us instead of waking for each message.
      tap_->receive_for(std::min<int64_t>(static_cast<int64_t>(ms) * 1000000LL, 150000), false);
    } else if (tap_) {
      tap_->receive_for(static_cast<int64_t>(ms) * 1000000LL, lockstep_);
    } else {
      bus_->handle_timeout(ms);
    }
  }

  /// Receives everything already sent.
  void receive_now() {
    if (tap_) {
      tap_->drain();
    } else {
      bus_->drain();
    }
  }

  /// Starts every process of the scenario but the external ones (whose commands it prints). A
  /// process the scenario replaces by a Python participant is `python -m nimble_rig.node`, with
  /// the rig's Python module found beside its executables.
  void start_processes() {
    const std::string bin_dir = options_.bin_dir.empty() ? self_dir() : options_.bin_dir;
    const std::string module_dir = python_module_dir(bin_dir);
    for (const auto& name : scenario_.processes) {
      const bool python = scenario_.participants.count(name) > 0;
      const std::string exe = python ? lc_.python : bin_dir + "/" + executable_of(name);
      std::vector<std::string> args = {"--name", name, "--scenario", resolved_file_, "--lcm-url", url_};
      if (python) args.insert(args.begin(), {"-m", "nimble_rig.node"});
      std::vector<std::string> environment;
      if (python && !module_dir.empty()) {
        const char* path = std::getenv("PYTHONPATH");
        environment.push_back("PYTHONPATH=" + module_dir + (path != nullptr && *path ? ":" + std::string(path) : ""));
      }
      if (external(name)) {
        std::cerr << "rig run: " << name << " is external: start it in this run's network"
                  << (ns_detail_.empty() || url_ != kNamespaceLcmUrl
                          ? ""
                          : " (nsenter -t " + std::to_string(::getpid()) + " -n)")
                  << " with\n  " << (environment.empty() ? "" : environment.front() + " ") << exe;
        for (const auto& a : args) std::cerr << " " << (a == url_ ? "'" + a + "'" : a);
        std::cerr << "\n";
        continue;
      }
      const int host_ns = host_link_ && plan_.hosts.host_index(name) > 0 ? host_link_->remote_namespace_fd() : -1;
      const std::string out = log_file_ + "." + name + ".out";
      supervisor_.start(name, exe, args, out, lc_.rig_cpus_for(lockstep_), host_ns, environment);
    }
    if (const std::string note = pin_to(lc_.rig_cpus_for(lockstep_)); !note.empty())
      std::cerr << "rig run: run." << (lockstep_ ? "lockstep_cpus" : "rig_cpus") << ": " << note << "\n";
    if (const std::string note = pin_to(lc_.launcher_cpus); !note.empty())
      std::cerr << "rig run: run.launcher_cpus: " << note << "\n";
    // Real time: the launcher only records and watches, so it yields the CPU to the rig's
    // processes. (In lockstep it paces the run through its acknowledgements instead.)
    if (!lockstep_) ::setpriority(PRIO_PROCESS, 0, 10);
  }

  bool external(const std::string& name) const {
    return std::find(lc_.external_processes.begin(), lc_.external_processes.end(), name) !=
           lc_.external_processes.end();
  }

  /// Asks every process to stop (RUN_CONTROL stop), then stops the ones the supervisor started.
  void stop_all(double grace_s) {
    const auto ask = [this] {
      run_control_t stop;
      stop.utime = transport::wall_us();
      stop.seq = run_control_seq_++;
      stop.command = run_control_t::COMMAND_STOP;
      stop.clock_mode = lockstep_ ? run_control_t::CLOCK_MODE_LOCKSTEP : run_control_t::CLOCK_MODE_REALTIME;
      stop.run_id = scenario_.name;
      stop.num_participants = 0;
      bus_->publish(contract::channels::kRunControl, stop);
    };
    const int64_t deadline = monotonic_ns() + static_cast<int64_t>(grace_s * 1e9);
    supervisor_.stop(grace_s, ask, [this] { receive_for(10); });
    // The external processes answer the same request; their last heartbeat and timing report
    // may come after the launcher's own children have exited.
    while (external_still_running() && monotonic_ns() < deadline) receive_for(10);
  }

  /// True if an external process has been heard and has not yet said it is stopping.
  bool external_still_running() const {
    for (const auto& name : lc_.external_processes) {
      const RunMonitor::Heartbeat* hb = monitor_.heartbeat(name);
      if (hb != nullptr && hb->state != heartbeat_t::STATE_STOPPING && hb->state != heartbeat_t::STATE_FAULT)
        return true;
    }
    return false;
  }

  /// Ends the run before its start with `message`: stops everything, keeps what was logged.
  int fail(const std::string& message, int code = kRunFailed) {
    std::cerr << "rig run: " << message << "\n";
    stop_all(0.5);
    receive_now();
    recorder_->close();
    if (recorder_->failed()) std::cerr << "rig run: " << recorder_->kept().failure << "\n";
    return code;
  }

  /// Every process must fly the run's configuration: a heartbeat with another digest is a process
  /// started with another scenario, or after a file the scenario names (model, manoeuvre,
  /// vehicle) changed. Returns what is wrong, or "".
  std::string digest_problem() const {
    for (const auto& name : scenario_.processes) {
      const RunMonitor::Heartbeat* hb = monitor_.heartbeat(name);
      if (hb == nullptr || hb->digest == run_digest_) continue;
      return "process '" + name + "' (pid " + std::to_string(hb->pid) +
             ") was started with another scenario: " + "configuration digest " +
             (hb->digest.empty() ? std::string("(none)") : hb->digest) + ", the run's " + run_digest_ +
             " (the scenario " + resolved_file_ +
             " and the files it names, as they were when the run started); refused. Start it with --scenario " +
             resolved_file_ + ", and change no model, manoeuvre or vehicle file during a run";
    }
    return "";
  }

  /// A running process that has gone silent without exiting (stopped, hung): published as a
  /// FAULT HEARTBEAT_LOST. Returns what, or "".
  std::string heartbeat_lost(int64_t now) {
    const int64_t limit = static_cast<int64_t>(lc_.heartbeat_timeout_s * 1e9);
    for (const auto& name : scenario_.processes) {
      const RunMonitor::Heartbeat* hb = monitor_.heartbeat(name);
      if (hb == nullptr || now - hb->recv_ns <= limit) continue;
      if (hb->state == heartbeat_t::STATE_STOPPING || hb->state == heartbeat_t::STATE_FAULT) continue;
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.1f s", 1e-9 * static_cast<double>(now - hb->recv_ns));
      const std::string what = "process '" + name + "' (pid " + std::to_string(hb->pid) + ") sent no heartbeat for " +
                               buf + " (run.heartbeat_timeout_s " + std::to_string(lc_.heartbeat_timeout_s) +
                               ") and has not exited: stopped or hung";
      FaultEvent f;
      f.utime = transport::wall_us();
      f.seq = launcher_fault_seq_++;
      f.rig_utime = static_cast<int64_t>(monitor_.sim_time_s() * 1e6);
      f.process = "launcher";
      f.severity = fault_event_t::SEVERITY_FATAL;
      f.code = fault_event_t::CODE_HEARTBEAT_LOST;
      f.channel = contract::channels::kHeartbeat;
      f.message = what;
      bus_->publish(contract::channels::kFault, contract::to_message(f));
      return "HEARTBEAT_LOST: " + what;
    }
    return "";
  }

  /// Waits for HEARTBEAT READY from every process, with the run's digest.
  int wait_ready() {
    const int64_t ready_deadline = monotonic_ns() + static_cast<int64_t>(lc_.ready_timeout_s * 1e9);
    for (;;) {
      receive_for(10);
      if (const ChildProcess* dead = supervisor_.reap()) {
        return fail("process '" + dead->name + "' " + dead->describe() + " before it was ready:\n" +
                    tail_of(dead->output_file, 12));
      }
      if (const std::string problem = digest_problem(); !problem.empty()) return fail(problem, kRunBadInput);
      bool all_ready = true;
      std::string waiting;
      for (const auto& name : scenario_.processes) {
        if (monitor_.heartbeat_state(name) != heartbeat_t::STATE_READY) {
          all_ready = false;
          waiting += (waiting.empty() ? "" : ", ") + name;
        }
      }
      if (all_ready && monitor_.heartbeat("plant") != nullptr) {
        // The digests of every READY heartbeat are in: the last check before the start.
        if (const std::string problem = digest_problem(); !problem.empty()) return fail(problem, kRunBadInput);
        return kRunOk;
      }
      if (g_launch_interrupted) return fail("interrupted while waiting for processes to be ready");
      if (monotonic_ns() > ready_deadline) {
        return fail("timed out after " + std::to_string(lc_.ready_timeout_s) +
                    " s waiting for HEARTBEAT READY from: " + waiting + hosts_hint(plan_.hosts, waiting));
      }
    }
  }

  /// Publishes RUN_CONTROL start (in real time at t0 = now + start_delay_s).
  run_control_t start_run() {
    run_control_t start;
    start.utime = transport::wall_us();
    start.seq = run_control_seq_++;
    start.command = run_control_t::COMMAND_START;
    start.clock_mode = lockstep_ ? run_control_t::CLOCK_MODE_LOCKSTEP : run_control_t::CLOCK_MODE_REALTIME;
    wall_start_ns_ = monotonic_ns();
    start.t0_monotonic_ns = lockstep_ ? 0 : wall_start_ns_ + static_cast<int64_t>(lc_.start_delay_s * 1e9);
    start.duration_ns = static_cast<int64_t>(std::llround(scenario_.duration_s * 1e9));
    start.run_id = scenario_.name + "-" + std::to_string(::getpid());
    for (const auto& p : scenario_.processes) {
      if (p != "plant") start.participants.push_back(p);
    }
    if (lockstep_) start.participants.push_back(LockstepLogger::kName);
    start.num_participants = static_cast<int32_t>(start.participants.size());
    bus_->publish(contract::channels::kRunControl, start);
    monitor_.set_t0(start.t0_monotonic_ns);
    if (options_.tap.state) options_.tap.state("running", "", 0.0);
    return start;
  }

  /// Watches the run until it completes, fails or is interrupted; returns the failure ("" if
  /// none). Resends the start to a process still waiting for it, prints the progress.
  std::string watch(run_control_t start, bool& interrupted) {
    const int64_t t0 = lockstep_ ? wall_start_ns_ : start.t0_monotonic_ns;
    int64_t next_progress_ns = wall_start_ns_;
    int64_t last_progress_truth = -1, last_progress_change_ns = wall_start_ns_;
    int resends = 0;
    // The checks below every kCheckPeriodNs, not after each of the run's messages.
    constexpr int64_t kCheckPeriodNs = 2000000;
    int64_t next_check_ns = 0;
    for (;;) {
      receive_for(5);
      const int64_t now = monotonic_ns();
      if (now < next_check_ns) continue;
      next_check_ns = now + kCheckPeriodNs;
      recorder_->flush_if_due(now);
      if (recorder_->failed()) return recorder_->kept().failure;
      if (const ChildProcess* dead = supervisor_.reap()) {
        receive_now();
        return died_during_run(*dead);
      }
      if (g_launch_interrupted) {
        interrupted = true;
        return "";
      }
      if (std::string failure = digest_problem(); !failure.empty()) return failure;
      if (std::string failure = heartbeat_lost(now); !failure.empty()) return failure;
      // Processes that missed the start command get it again.
      if (resends < 5 && now - wall_start_ns_ > (resends + 1) * 300000000LL) {
        bool someone_waiting = false;
        for (const auto& name : scenario_.processes) {
          someone_waiting |= monitor_.heartbeat_state(name) == heartbeat_t::STATE_READY;
        }
        if (someone_waiting) {
          start.seq = run_control_seq_++;
          bus_->publish(contract::channels::kRunControl, start);
        }
        ++resends;
      }
      bool done = false;
      if (lockstep_) {
        done = monitor_.heartbeat_state("plant") == heartbeat_t::STATE_FINISHED;
        if (monitor_.truth_count() != last_progress_truth) {
          last_progress_truth = monitor_.truth_count();
          last_progress_change_ns = now;
        } else if (now - last_progress_change_ns > static_cast<int64_t>(lc_.stall_timeout_s * 1e9)) {
          return "lockstep run stalled: no new TRUTH for " + std::to_string(lc_.stall_timeout_s) +
                 " s at t = " + std::to_string(monitor_.sim_time_s()) + " s";
        }
      } else {
        done = now >= t0 + start.duration_ns + 20000000LL;
      }
      if (done) return "";
      if (options_.progress && now >= next_progress_ns) next_progress_ns = print_progress(now);
    }
  }

  /// A process that ended during the run: what, when and its last fatal fault (on the first line,
  /// which the result keeps), then its output.
  std::string died_during_run(const ChildProcess& dead) const {
    std::string why;
    for (auto it = monitor_.faults().rbegin(); it != monitor_.faults().rend(); ++it) {
      if (it->process == dead.name && it->severity >= 3) {
        why = "; its last fatal fault: " + it->message.substr(0, it->message.find('\n'));
        break;
      }
    }
    return "process '" + dead.name + "' (pid " + std::to_string(dead.pid) + ") " + dead.describe() +
           " during the run at simulated t = " + std::to_string(monitor_.sim_time_s()) + " s" + why +
           "\n  last output (" + dead.output_file + "):\n" + tail_of(dead.output_file, 8);
  }

  /// One progress line on stderr (rewritten in place on a terminal); returns when the next is due.
  int64_t print_progress(int64_t now) const {
    const bool tty = ::isatty(STDERR_FILENO);
    const double wall = static_cast<double>(now - wall_start_ns_) / 1e9;
    char buf[200];
    std::snprintf(buf, sizeof buf, "[%s] sim %7.2f / %.2f s   wall %7.2f s   %6.1fx   TRUTH %lld   faults %zu",
                  scenario_.clock.c_str(), monitor_.sim_time_s(), scenario_.duration_s, wall,
                  wall > 0 ? monitor_.sim_time_s() / wall : 0.0, static_cast<long long>(monitor_.truth_count()),
                  monitor_.faults().size());
    if (tty)
      std::fprintf(stderr, "\r%s", buf);
    else
      std::fprintf(stderr, "%s\n", buf);
    return now + (tty ? 200000000LL : 2000000000LL);
  }

  /// Judges the run and writes its report.
  int report(const std::string& failure, bool interrupted, double wall_s) {
    RunReport report;
    report.scenario = scenario_.name;
    report.clock = scenario_.clock;
    report.seed = scenario_.seed;
    report.config_digest = run_digest_;
    report.transport = url_;
    report.transport_detail = ns_detail_;
    report.log_file = log_file_;
    report.log = recorder_->kept();
    fill_from_monitor(report, monitor_, monitor_.sim_time_s(), wall_s);
    for (const auto& c : supervisor_.children()) {
      report.processes.push_back(ProcessOutcome{c.name, c.pid, c.exited, c.exit_code, c.signal, c.describe(), 0, ""});
    }
    for (const auto& name : lc_.external_processes) {
      const RunMonitor::Heartbeat* hb = monitor_.heartbeat(name);
      const bool stopped = hb != nullptr && hb->state == heartbeat_t::STATE_STOPPING;
      report.processes.push_back(ProcessOutcome{name, hb != nullptr ? hb->pid : -1, stopped, stopped ? 0 : -1, 0,
                                                hb == nullptr ? "external, never heard"
                                                : stopped     ? "external, stopped"
                                                              : "external, still running",
                                                0, ""});
    }
    describe_processes(report, scenario_, monitor_);
    report.hosts = host_summaries(plan_.hosts, host_link_.get());
    report.verdict = judge_run(report.flight, plan_.judge, interrupted, failure,
                               judge_timing(report.timing, plan_.judge, !lockstep_), options_.strict_timing,
                               failsafe_of(monitor_), judge_tracking(report.tracking, plan_.judge));
    if (!failure.empty()) std::cerr << "rig run: " << failure << "\n";
    return finish_report(report, options_);
  }

  RunPlan& plan_;
  const RunOptions& options_;
  Scenario& scenario_;
  const LaunchConfig& lc_;
  const bool lockstep_;
  std::string url_, ns_detail_;
  bool in_ns_ = false;
  std::unique_ptr<HostLink> host_link_;
  std::string log_file_, resolved_file_;
  std::string run_digest_;  ///< the resolved scenario and the files it names, read when the run starts
  std::unique_ptr<transport::Bus> bus_;
  std::unique_ptr<transport::MulticastTap> tap_;  ///< the run's messages over udpm (else bus_'s)
  RunMonitor monitor_;
  std::unique_ptr<Recorder> recorder_;
  ProcessSupervisor supervisor_;
  int64_t run_control_seq_ = 0, launcher_fault_seq_ = 0;
  std::unique_ptr<LockstepLogger> logger_;
  int64_t wall_start_ns_ = 0;
};

int run_processes(RunPlan& plan, const RunOptions& options) { return ProcessRun(plan, options).run(); }

}  // namespace
}  // namespace nimble::launcher
