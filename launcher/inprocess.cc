#include "launcher/inprocess.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <exception>
#include <functional>
#include <iostream>
#include <memory>
#include <vector>

#include <nimble/run_control_t.hpp>

#include "can_bridge/bridge_config.h"
#include "can_bridge/bridge_node.h"
#include "can_bridge/inprocess_can_bus.h"
#include "contract/channels.h"
#include "controller/controller_node.h"
#include "estimator/estimator_node.h"
#include "launcher/message_pipe.h"
#include "launcher/recorder.h"
#include "mocap/mocap_node.h"
#include "plant/plant_node.h"
#include "transport/bus.h"
#include "transport/clock.h"
#include "transport/inprocess_hub.h"
#include "transport/node.h"

namespace nimble::launcher {
namespace {

using transport::monotonic_ns;

volatile std::sig_atomic_t g_flight_interrupted = 0;
extern "C" void on_inprocess_interrupt(int) {
  g_flight_interrupted = 1;
  transport::ProcessNode::request_stop();
}

/// One process of the run, built in this process.
struct Process {
  std::string name;
  transport::ProcessNode* node = nullptr;
  std::function<int()> run;      ///< the lockstep master only: flies the run
  std::function<void()> finish;  ///< participants: after the run, before their last health report
  std::shared_ptr<void> owner;
};

template <typename Node>
Process make(const std::string& name, std::shared_ptr<Node> n) {
  Process p;
  p.name = name;
  p.node = &n->node();
  p.run = [n] { return n->run(); };
  p.owner = n;
  return p;
}

Process make_process(const std::string& name, const Scenario& scenario, transport::InprocessHub& hub,
                     can::InprocessCanBus& can_bus, const InprocessOptions& options) {
  const transport::NodeOptions o{name, scenario.file, "inprocess", &hub};
  if (const auto it = options.replace.find(name); it != options.replace.end()) {
    const CustomParticipant c = it->second(o);
    if (c.node == nullptr) throw std::invalid_argument("the participant in place of " + name + " has no process node");
    Process p;
    p.name = name;
    p.node = c.node;
    p.owner = c.owner;
    return p;
  }
  if (name == "plant") return make(name, std::make_shared<plant::PlantNode>(scenario, o));
  if (name == "controller") return make(name, std::make_shared<ControllerNode>(scenario, o));
  if (name == "mocap") return make(name, std::make_shared<MocapNode>(scenario, o));
  if (name == "estimator") return make(name, std::make_shared<EstimatorNode>(scenario, o));
  if (name == can::kFlightProcess || name == can::kRigProcess) {
    auto n = std::make_shared<can::CanBridgeNode>(scenario, o, &can_bus);
    Process p = make(name, n);
    p.finish = [n] {
      n->drain_socket();
      n->publish_health();
    };
    return p;
  }
  throw ConfigError(scenario.file, "processes", name,
                    "unknown process (known: plant, controller, mocap, estimator, can_flight, can_rig)");
}

std::string last_fatal_fault(const RunMonitor& monitor) {
  for (auto it = monitor.faults().rbegin(); it != monitor.faults().rend(); ++it) {
    if (it->severity >= 3) return "'" + it->process + "': " + it->message;
  }
  return "";
}

/// The progress line of the run: simulated and wall time, speed, TRUTH messages.
void print_progress(const RunMonitor& monitor, double duration_s, double wall, bool tty) {
  char line[160];
  std::snprintf(line, sizeof line, "[inprocess] sim %7.2f / %.2f s   wall %7.2f s   %7.1fx   TRUTH %lld",
                monitor.sim_time_s(), duration_s, wall, wall > 0 ? monitor.sim_time_s() / wall : 0.0,
                static_cast<long long>(monitor.truth_count()));
  std::fprintf(stderr, tty ? "\r%s" : "%s\n", line);
}

/// Builds the run's processes; returns the lockstep master, the plant (the others join in process).
Process* build_processes(const Scenario& s, transport::InprocessHub& hub, can::InprocessCanBus& can_bus,
                         const InprocessOptions& options, std::vector<Process>& processes) {
  for (const auto& [name, factory] : options.replace) {
    if (name == "plant")
      throw ConfigError(s.file, "processes", name, "the plant, the lockstep master, cannot be replaced");
    if (std::find(s.processes.begin(), s.processes.end(), name) == s.processes.end()) {
      throw ConfigError(s.file, "processes", name, "a participant in place of a process the scenario does not run");
    }
  }
  // A participant the scenario names flies in process only as a Python object (nimble_rig.fly()
  // makes it from the section): the rig's own process in its place would be another run.
  for (const auto& [name, spec] : s.participants) {
    if (options.replace.count(name) == 0) {
      throw ConfigError(s.file, "participants." + name, spec.python_file,
                        "a Python participant flies in process only from Python (nimble_rig.fly(scenario)); the rig "
                        "tool embeds no Python: run it with --clock lockstep or realtime, where it is its own process");
    }
  }
  Process* master = nullptr;
  for (const auto& name : s.processes) processes.push_back(make_process(name, s, hub, can_bus, options));
  for (auto& p : processes) {
    if (p.name == "plant")
      master = &p;
    else
      p.node->join_inprocess();
  }
  if (master == nullptr) throw ConfigError(s.file, "processes", "", "a run needs the process plant");
  return master;
}

/// The START message: the run's lockstep clock, duration, id and participants (all but the master).
run_control_t start_message(const Scenario& s, const std::vector<Process>& processes, const Process* master) {
  run_control_t start;
  start.utime = transport::wall_us();
  start.seq = 0;
  start.command = run_control_t::COMMAND_START;
  start.clock_mode = run_control_t::CLOCK_MODE_LOCKSTEP;
  start.t0_monotonic_ns = 0;
  start.duration_ns = static_cast<int64_t>(std::llround(s.duration_s * 1e9));
  start.run_id = s.name + "-" + std::to_string(::getpid());
  for (const auto& p : processes) {
    if (&p != master) start.participants.push_back(p.name);
  }
  start.num_participants = static_cast<int32_t>(start.participants.size());
  return start;
}

/// Flies the run: the master's loop, then each participant's finish; returns what a process threw, if one did.
std::string fly_processes(Process* master, std::vector<Process>& processes, int& master_code) {
  std::string failure;
  try {
    master_code = master->run();
    for (auto& p : processes) {
      if (&p == master) continue;
      if (p.finish) p.finish();
      p.node->finish_inprocess();
    }
  } catch (const std::exception& e) {
    failure = "a process threw during the run at simulated t = " +
              std::to_string(static_cast<double>(master->node->sim_time_ns()) / 1e9) + " s: " + e.what();
  }
  return failure;
}

/// How the flight ended.
struct Ending {
  int master_code = transport::kExitOk;
  std::string failure;
  bool interrupted = false;
  double wall_s = 0.0;
};

/// The run's report: what was flown, how, the monitor's figures, each process's outcome and the verdict.
RunReport report_of(const RunPlan& plan, const InprocessOptions& options, int64_t published, const Recorder* recorder,
                    const RunMonitor& monitor, const std::vector<Process>& processes, const Process* master,
                    const Ending& end) {
  const Scenario& s = plan.scenario;
  RunReport report;
  report.scenario = s.name;
  report.clock = kClockInprocess;
  report.seed = s.seed;
  if (options.config_digest) report.config_digest = scenario_digest(s);
  report.transport = "in process";
  report.transport_detail = "one thread, no transport; " + std::to_string(published) + " messages" +
                            (plan.hosts.split() ? "; the hosts section does not apply in process" : "");
  report.log_file = options.log_file;
  if (recorder) report.log = recorder->kept();
  fill_from_monitor(report, monitor, monitor.sim_time_s(), end.wall_s);
  for (const auto& p : processes) {
    const int code = &p == master ? end.master_code : transport::kExitOk;
    report.processes.push_back(ProcessOutcome{p.name, static_cast<long long>(::getpid()), true, code, 0,
                                              "in process, returned " + std::to_string(code), 0, ""});
  }
  describe_processes(report, plan.scenario, monitor);
  report.verdict = judge_run(report.flight, plan.judge, end.interrupted, end.failure, {}, false, failsafe_of(monitor),
                             judge_tracking(report.tracking, plan.judge));
  return report;
}

}  // namespace

RunReport fly_inprocess(const RunPlan& plan, const InprocessOptions& options) {
  const Scenario& s = plan.scenario;
  transport::InprocessHub hub;
  RunMonitor monitor(monitor_config(plan));
  std::unique_ptr<Recorder> recorder;
  if (!options.log_file.empty()) {
    recorder = std::make_unique<Recorder>(options.log_file, monitor, LogStamps::kSimulated);
    recorder->set_max_bytes(options.log_max_bytes);
  }
  // Set by the recording thread when the log can no longer be written: the flight then ends.
  std::atomic<bool> record_failed{false};

  // Every message goes, in order, to a second thread that records and monitors it (the
  // launcher's logger, in the other executors); the flight never waits for the disk.
  const bool tty = ::isatty(STDERR_FILENO);
  std::atomic<int64_t> wall_start_ns{monotonic_ns()};
  int64_t next_progress_ns = 0;  // the recording thread's own
  MessagePipe pipe([&](const std::string& channel, const void* data, int size, int64_t sent_ns, bool own_encoding) {
    // Stamped on arrival here, as the launcher's logger stamps what it receives; the log's
    // events up to the first tick by their publication, which places the run's simulated time.
    const int64_t recv_ns = monotonic_ns();
    if (recorder) {
      recorder->record(channel, data, size, sent_ns > 0 ? sent_ns : recv_ns, own_encoding);
      recorder->flush_if_due(recv_ns);
      if (recorder->failed()) record_failed.store(true, std::memory_order_relaxed);
    } else {
      monitor.on_message(channel, data, size, recv_ns, own_encoding);
    }
    if (options.on_message) options.on_message(channel, data, size);
    if (options.progress && recv_ns >= next_progress_ns && channel == contract::channels::kTruth) {
      const double wall = static_cast<double>(recv_ns - wall_start_ns) / 1e9;
      print_progress(monitor, s.duration_s, wall, tty);
      next_progress_ns = recv_ns + (tty ? 200000000LL : 2000000000LL);
    }
  });
  bool ticked = false;  // the first RIG_CLOCK tick has gone to the log
  hub.subscribe(".*", [&pipe, &hub, &ticked](const std::string& channel, const void* data, int size) {
    int64_t sent_ns = 0;  // after the first tick the log's events follow simulated time
    if (!ticked) {
      sent_ns = monotonic_ns();
      ticked = channel == contract::channels::kRigClock;
    }
    pipe.send(&channel, data, size, sent_ns, hub.delivering_own_encoding());
  });

  can::InprocessCanBus can_bus;
  std::vector<Process> processes;
  Process* master = build_processes(s, hub, can_bus, options, processes);
  transport::ProcessNode* master_node = master->node;
  master_node->on_housekeeping([&record_failed, master_node] {
    if (record_failed.load(std::memory_order_relaxed)) master_node->end_run();
  });

  transport::Bus control(hub);
  run_control_t start = start_message(s, processes, master);
  wall_start_ns = monotonic_ns();  // the run starts here; building it is not timed
  control.publish(contract::channels::kRunControl, start);
  hub.drain();

  g_flight_interrupted = 0;
  struct sigaction sa {
  }, old_int{}, old_term{};
  sa.sa_handler = on_inprocess_interrupt;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, &old_int);
  sigaction(SIGTERM, &sa, &old_term);

  int master_code = transport::kExitOk;
  std::string failure = fly_processes(master, processes, master_code);
  run_control_t stop = start;
  stop.seq = 1;
  stop.utime = transport::wall_us();
  stop.command = run_control_t::COMMAND_STOP;
  control.publish(contract::channels::kRunControl, stop);
  hub.drain();
  pipe.close();  // every message recorded and monitored
  bool interrupted = g_flight_interrupted != 0;
  if (recorder) {
    recorder->close();
    // A log that lost messages is the run's failure, whatever else ended it.
    if (recorder->failed()) {
      failure = recorder->kept().failure;
      interrupted = false;
    }
  }
  const double wall_s = static_cast<double>(monotonic_ns() - wall_start_ns) / 1e9;
  sigaction(SIGINT, &old_int, nullptr);
  sigaction(SIGTERM, &old_term, nullptr);
  if (options.progress && tty) std::fprintf(stderr, "\n");
  if (failure.empty() && master_code != transport::kExitOk) {
    const std::string why = last_fatal_fault(monitor);
    failure = "the lockstep master (plant) ended with code " + std::to_string(master_code) +
              " at simulated t = " + std::to_string(monitor.sim_time_s()) + " s" + (why.empty() ? "" : ": " + why);
  }

  return report_of(plan, options, hub.published(), recorder.get(), monitor, processes, master,
                   Ending{master_code, failure, interrupted, wall_s});
}

int run_inprocess(const RunPlan& plan_in, const RunOptions& options) {
  RunPlan plan = plan_in;
  const std::string log_file = log_file_for(plan, options);
  RunReport report;
  try {
    place_candump_log(plan, log_file);
    write_resolved_scenario(plan, log_file);
    InprocessOptions o;
    o.log_file = log_file;
    o.log_max_bytes = options.log_max_bytes;
    o.progress = options.progress;
    o.on_message = options.tap.message;
    if (options.tap.start) options.tap.start();
    if (options.tap.state) options.tap.state("running", "", 0.0);
    report = fly_inprocess(plan, o);
  } catch (const ConfigError& e) {
    std::cerr << "rig run: config error: " << e.what() << "\n";
    return kRunBadInput;
  } catch (const std::exception& e) {
    std::cerr << "rig run: " << e.what() << "\n";
    return kRunBadInput;
  }
  if (report.verdict.exit_code == kRunFailed) std::cerr << "rig run: " << report.verdict.text << "\n";
  return finish_report(report, options);
}

}  // namespace nimble::launcher
