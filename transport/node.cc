// ProcessNode (transport/node.h): its tasks and inputs, the wait for the start and the stop, and
// the real-time loop. The health messages: node_health.cc; the lockstep clock: node_lockstep.cc.

#include "transport/node.h"

#include <poll.h>
#include <sched.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include <nimble/rig_clock_t.hpp>
#include <nimble/timing_health_t.hpp>

namespace nimble::transport {

volatile std::sig_atomic_t ProcessNode::stop_requested_ = 0;

namespace {

extern "C" void on_stop_signal(int) { ProcessNode::request_stop(); }

}  // namespace

ProcessNode::ProcessNode(std::string name, const std::string& lcm_url, std::string config_digest)
    : ProcessNode(NodeOptions{std::move(name), "", lcm_url, nullptr}, std::move(config_digest)) {}

ProcessNode::ProcessNode(const NodeOptions& options, std::string config_digest)
    : ProcessNode(options, RealtimeSettings{}, std::move(config_digest)) {}

ProcessNode::ProcessNode(const NodeOptions& options, const RealtimeSettings& realtime, std::string config_digest)
    : name_(options.name),
      config_digest_(std::move(config_digest)),
      bus_(options.hub != nullptr ? Bus(*options.hub) : Bus(options.lcm_url)),
      late_threshold_ns_(realtime.late_threshold_ns) {
  spin_ns_ = realtime.spin_ns;
  if (options.hub == nullptr) start_wait_ns_ = realtime.start_wait_ns;
  bus_.enable_channel_filter(realtime.channel_filter);
  bus_.on_malformed([this](const std::string& channel, const std::string& what) {
    fault(fault_event_t::SEVERITY_WARNING, fault_event_t::CODE_MESSAGE_MALFORMED, channel,
          "dropped a malformed message on " + channel + ": " + what);
  });
  // Subscribed before anything is announced, so that no start command is missed.
  bus_.subscribe<run_control_t>(contract::channels::kRunControl, [this](const run_control_t& m) { on_run_control(m); });
  if (options.hub == nullptr && !realtime_problem().empty()) {
    fault(fault_event_t::SEVERITY_WARNING, fault_event_t::CODE_REALTIME_UNAVAILABLE, "", realtime_problem());
  }
}

void ProcessNode::install_signal_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGINT, &sa, nullptr);
}

void ProcessNode::add_task(const std::string& label, double rate_hz, TaskFn fn, Trigger trigger, int64_t backstop_ns) {
  const double period = 1e9 / rate_hz;
  if (!(rate_hz > 0.0) || std::fabs(period - std::round(period)) > 1e-6) {
    throw std::invalid_argument("task '" + label + "': rate " + std::to_string(rate_hz) +
                                " Hz does not give a whole number of nanoseconds per period");
  }
  tasks_.push_back(Task{label, static_cast<int64_t>(std::llround(period)), std::move(fn), trigger, 0,
                        trigger == Trigger::kInput ? std::max<int64_t>(0, backstop_ns) : 0});
}

void ProcessNode::run_deferred() {
  for (auto& fn : deferred_) fn();
  deferred_.clear();
}

void ProcessNode::notify_input(int64_t input_sim_time_ns) {
  if (!started_ || stop_ || clock_mode_ != run_control_t::CLOCK_MODE_REALTIME) return;
  for (auto& t : tasks_) {
    if (t.trigger != Trigger::kInput || t.next_ns > input_sim_time_ns || t.next_ns >= duration_ns_) continue;
    // Lateness of the cycle behind the triggering input's own time.
    jitter_.add_ns(monotonic_ns() - (t0_ns_ + input_sim_time_ns));
    ++loop_count_;
    sim_time_ns_ = t.next_ns;
    t.fn(t.next_ns);
    // Next cycle: the first period boundary after this input (missed cycles are skipped).
    const int64_t skipped = (input_sim_time_ns - t.next_ns) / t.period_ns;
    overruns_ += skipped;
    t.next_ns += (skipped + 1) * t.period_ns;
    run_deferred();
  }
}

void ProcessNode::watch_fd(int fd, std::function<void()> on_readable) {
  watched_.push_back(Watched{fd, std::move(on_readable)});
}

int ProcessNode::wait_io(int64_t timeout_ns) {
  if (inprocess()) return bus_.drain();  // everything published so far, and what it causes
  std::vector<pollfd> fds;
  fds.reserve(1 + watched_.size());
  fds.push_back(pollfd{bus_.fileno(), POLLIN, 0});
  for (const auto& w : watched_) fds.push_back(pollfd{w.fd, POLLIN, 0});
  const int64_t t = std::max<int64_t>(0, timeout_ns);
  timespec ts{t / 1000000000LL, t % 1000000000LL};
  const int n = ::ppoll(fds.data(), fds.size(), &ts, nullptr);
  if (n <= 0) return 0;
  if (fds[0].revents & POLLIN) bus_.handle();
  for (std::size_t i = 1; i < fds.size(); ++i) {
    if (fds[i].revents & (POLLIN | POLLERR)) watched_[i - 1].on_readable();
  }
  return n;
}

void ProcessNode::on_run_control(const run_control_t& msg) {
  if (msg.command == run_control_t::COMMAND_STOP) {
    stop_ = true;
    return;
  }
  if (msg.command == run_control_t::COMMAND_START && !started_) {
    started_ = true;
    clock_mode_ = msg.clock_mode;
    t0_ns_ = msg.t0_monotonic_ns;
    duration_ns_ = msg.duration_ns;
    run_id_ = msg.run_id;
    participants_ = msg.participants;
    if (clock_mode_ == run_control_t::CLOCK_MODE_REALTIME) bus_.set_deadlines(t0_ns_, late_threshold_ns_);
    if (inprocess() && !master_) {
      started_wall_us_ = wall_us();
      publish_heartbeat(heartbeat_t::STATE_RUNNING);
    }
  }
}

void ProcessNode::join_inprocess() {
  subscribe_lockstep_side();
  publish_heartbeat(heartbeat_t::STATE_READY);
}

void ProcessNode::finish_inprocess() {
  publish_heartbeat(heartbeat_t::STATE_FINISHED);
  publish_timing_health();
  publish_heartbeat(heartbeat_t::STATE_STOPPING);
}

bool ProcessNode::wait_for_start() {
  if (!bus_.channel_filter_problem().empty()) {
    fault(fault_event_t::SEVERITY_WARNING, fault_event_t::CODE_REALTIME_UNAVAILABLE, "",
          "kernel channel filter not applied: " + bus_.channel_filter_problem() +
              "; every message of the run wakes this process");
  }
  publish_heartbeat(heartbeat_t::STATE_READY);
  const int64_t give_up_ns = start_wait_ns_ > 0 ? monotonic_ns() + start_wait_ns_ : kNever;
  while (!started_ && !stop_) {
    if (monotonic_ns() >= give_up_ns) {
      start_wait_expired_ = true;
      return false;
    }
    wait_io(20000000);
    housekeeping();
  }
  return started_ && !stop_;
}

int64_t ProcessNode::next_due_ns() const {
  int64_t due = kNever;
  for (const auto& t : tasks_) {
    if (t.next_ns < duration_ns_) due = std::min(due, t.next_ns);
  }
  return due;
}

void ProcessNode::idle_until_stopped() {
  publish_heartbeat(heartbeat_t::STATE_FINISHED);
  publish_timing_health();
  if (inprocess()) return;  // nobody else runs until this returns
  while (!stop_) {
    wait_io(50000000);
    housekeeping();
  }
}

int ProcessNode::run() {
  if (inprocess() && !master_) throw std::logic_error("in process only the lockstep master runs; see join_inprocess()");
  subscribe_lockstep_side();
  if (!wait_for_start()) {
    if (start_wait_expired_) {
      // Started by hand for a run that was refused, or whose launcher is gone: nobody will start
      // or stop this process, so it ends, saying why.
      char waited[32];
      std::snprintf(waited, sizeof waited, "%.1f s", 1e-9 * static_cast<double>(start_wait_ns_));
      const std::string why = "no run started within " + std::string(waited) +
                              " (run.start_wait_s): the run was refused or its launcher is gone; giving up";
      fault(fault_event_t::SEVERITY_ERROR, fault_event_t::CODE_COMMAND_TIMEOUT, contract::channels::kRunControl, why);
      std::fprintf(stderr, "%s: %s\n", name_.c_str(), why.c_str());
      publish_heartbeat(heartbeat_t::STATE_STOPPING);
      return kExitFault;
    }
    publish_heartbeat(heartbeat_t::STATE_STOPPING);
    return kExitOk;
  }
  started_wall_us_ = wall_us();
  publish_heartbeat(heartbeat_t::STATE_RUNNING);
  if (has_pending_tick_) {
    // The master's first tick overtook RUN_CONTROL start (they come from different senders).
    has_pending_tick_ = false;
    if (pending_tick_.run_id == run_id_) on_rig_clock(pending_tick_);
  }
  int code = kExitOk;
  if (clock_mode_ == run_control_t::CLOCK_MODE_REALTIME) {
    code = run_realtime();
  } else if (master_) {
    code = run_lockstep_master();
  } else {
    code = run_lockstep_participant();
  }
  publish_timing_health();
  publish_heartbeat(code == kExitOk ? heartbeat_t::STATE_STOPPING : heartbeat_t::STATE_FAULT);
  return code;
}

int ProcessNode::run_realtime() {
  use_fine_timer_slack();
  while (!stop_) {
    Task* task = nullptr;
    for (auto& t : tasks_) {
      if (t.timed() && t.next_ns < duration_ns_ && (task == nullptr || t.deadline_ns() < task->deadline_ns()))
        task = &t;
    }
    if (task == nullptr) {
      // Only input-triggered tasks (or timed ones done): they run from notify_input() while
      // messages are handled.
      bool due = false;
      for (const auto& t : tasks_) due = due || t.next_ns < duration_ns_;
      if (!due || (t0_ns_ + duration_ns_ <= monotonic_ns())) break;
      wait_io(10000000);
      housekeeping();
      continue;
    }
    const int64_t deadline = t0_ns_ + task->deadline_ns();
    for (;;) {
      const int64_t now = monotonic_ns();
      if (now >= deadline || stop_) break;
      if (t0_ns_ + task->deadline_ns() != deadline) break;  // its input came: it ran (notify_input)
      if (deadline - now <= spin_ns_) {
        bus_.drain();  // spin to the deadline, still handling messages
        if (!watched_.empty()) wait_io(0);
        continue;
      }
      wait_io(deadline - now - spin_ns_);
      housekeeping();
    }
    if (stop_) break;
    // An input-triggered task on its backstop: first what has arrived (this process may itself
    // have been held up), which runs it through notify_input if its input is there after all.
    if (task->trigger == Trigger::kInput) bus_.drain();
    if (monotonic_ns() < t0_ns_ + task->deadline_ns()) continue;
    jitter_.add_ns(monotonic_ns() - deadline);
    ++loop_count_;
    sim_time_ns_ = task->next_ns;
    task->fn(task->next_ns);
    run_deferred();
    task->next_ns += task->period_ns;
    if (monotonic_ns() > t0_ns_ + task->next_ns) ++overruns_;
    housekeeping();
  }
  if (!stop_) idle_until_stopped();
  return kExitOk;
}

}  // namespace nimble::transport
