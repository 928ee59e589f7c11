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

#include "cmdline/args.h"

namespace nimble::transport {

volatile std::sig_atomic_t ProcessNode::stop_requested_ = 0;

namespace {

constexpr int64_t kNever = std::numeric_limits<int64_t>::max();

extern "C" void on_stop_signal(int) { ProcessNode::request_stop(); }

}  // namespace

std::string apply_realtime_priority(int priority) {
  if (priority <= 0) return "";
  sched_param sp{};
  sp.sched_priority = priority;
  if (::sched_setscheduler(0, SCHED_FIFO, &sp) != 0) {
    return std::string("cannot run under SCHED_FIFO priority ") + std::to_string(priority) + ": " +
           std::strerror(errno) + " (needs root or CAP_SYS_NICE); running with the default scheduler";
  }
  if (::mlockall(MCL_CURRENT | MCL_FUTURE) != 0) {
    return std::string("SCHED_FIFO set, but mlockall failed: ") + std::strerror(errno);
  }
  return "";
}

namespace {
std::string& realtime_problem_storage() {
  static std::string why;
  return why;
}
}  // namespace

void set_realtime_problem(const std::string& why) { realtime_problem_storage() = why; }
const std::string& realtime_problem() { return realtime_problem_storage(); }

std::optional<int> parse_node_options(int argc, char** argv, const std::string& program,
                                      const std::string& default_name, NodeOptions& options) {
  NodeOptions o;
  o.name = default_name;
  cli::CommandLine cl(program, "The rig's " + default_name +
                                   " process. 'rig run' starts it with the resolved scenario it writes next to\n"
                                   "the log and the run's LCM URL; it announces HEARTBEAT READY, waits for RUN_CONTROL\n"
                                   "start and runs until stopped.");
  cl->footer("Exit code: 0 stopped cleanly, 2 bad command line or configuration, 3 a lockstep participant\n"
             "did not acknowledge in time, 4 another fatal fault.");
  cl->add_option("--scenario", o.scenario_file, "the resolved scenario YAML (rig run writes it next to the log)")
      ->type_name("FILE")
      ->required();
  cl->add_option("--name", o.name, "the process name on HEARTBEAT, FAULT and STEP_ACK")
      ->type_name("NAME")
      ->capture_default_str();
  cl->add_option("--lcm-url", o.lcm_url,
                 "the run's LCM URL (default: LCM's, that is LCM_DEFAULT_URL or udpm://239.255.76.67:7667)")
      ->type_name("URL");
  if (const auto done = cl.parse(argc, argv)) return *done == 0 ? kExitOk : kExitConfig;
  options = std::move(o);
  return std::nullopt;
}

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
  bus_.enable_channel_filter(realtime.channel_filter);
  bus_.on_malformed([this](const std::string& channel, const std::string& what) {
    fault(fault_event_t::SEVERITY_WARNING, fault_event_t::CODE_MESSAGE_MALFORMED, channel,
          "dropped a malformed message on " + channel + ": " + what);
  });
  // Subscribed before anything is announced, so that no start command is missed.
  bus_.subscribe<run_control_t>(contract::channels::kRunControl,
                                [this](const run_control_t& m) { on_run_control(m); });
  if (options.hub == nullptr && !realtime_problem().empty()) {
    fault(fault_event_t::SEVERITY_WARNING, fault_event_t::CODE_REALTIME_UNAVAILABLE, "", realtime_problem());
  }
}

void ProcessNode::install_signal_handlers() {
  struct sigaction sa{};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGTERM, &sa, nullptr);
  sigaction(SIGINT, &sa, nullptr);
}

void ProcessNode::add_task(const std::string& label, double rate_hz, TaskFn fn, Trigger trigger,
                           int64_t backstop_ns) {
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

void ProcessNode::publish_ack(int64_t step, int64_t utime) {
  last_acked_step_ = step;
  step_ack_t ack;
  ack.utime = utime;
  ack.seq = ack_seq_++;
  ack.step = step;
  ack.next_due_ns = next_due_ns();
  ack.process = name_;
  bus_.publish(contract::channels::kStepAck, ack);
}

void ProcessNode::release_ack() {
  ack_hold_requested_ = false;  // released within the task itself: nothing to hold
  if (!ack_held_) return;
  ack_held_ = false;
  publish_ack(held_step_, held_utime_);
  run_deferred();
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

void ProcessNode::fault(int8_t severity, int32_t code, const std::string& channel, const std::string& message,
                        int64_t rig_utime_us) {
  const int64_t second = monotonic_ns() / 1000000000LL;
  auto& [sec, count] = fault_budget_[code];
  if (sec != second) {
    sec = second;
    count = 0;
  }
  if (++count > 10) return;
  fault_event_t f;
  f.utime = wall_us();
  f.seq = fault_seq_++;
  f.rig_utime = rig_utime_us >= 0 ? rig_utime_us : sim_time_ns_ / 1000;
  f.process = name_;
  f.severity = severity;
  f.code = code;
  f.channel = channel;
  f.message = message;
  bus_.publish(contract::channels::kFault, f);
}

void ProcessNode::inject_faults(const std::vector<contract::FaultSpec>& faults, uint64_t seed) {
  bool any = false;
  for (const auto& f : faults) any |= f.target != contract::kFaultTargetCan;
  if (!any) return;
  bus_.set_fault_injector(std::make_unique<FaultInjector>(
      faults, seed, [this](const contract::FaultSpec& f, bool began, int64_t utime) {
        char when[48];
        std::snprintf(when, sizeof when, " at t = %.3f s", 1e-6 * static_cast<double>(utime));
        fault(fault_event_t::SEVERITY_INFO, fault_event_t::CODE_FAULT_INJECTED, f.target,
              "injected " + f.describe() + (began ? " began" : " ended") + when, utime);
      }));
}

void ProcessNode::publish_heartbeat(int8_t state) {
  hb_state_ = state;
  heartbeat_t hb;
  hb.utime = wall_us();
  hb.seq = hb_seq_++;
  hb.process = name_;
  hb.pid = static_cast<int32_t>(::getpid());
  hb.state = state;
  hb.config_digest = config_digest_;
  bus_.publish(contract::channels::kHeartbeat, hb);
  next_heartbeat_us_ = hb.utime + (state == heartbeat_t::STATE_READY ? 100000 : 500000);
}

void ProcessNode::publish_timing_health() {
  const int64_t now = wall_us();
  timing_health_t h;
  h.utime = now;
  h.seq = health_seq_++;
  h.process = name_;
  h.window_us = started_wall_us_ > 0 ? now - started_wall_us_ : 0;
  h.loop_rate_hz = tasks_.empty() ? 0.0 : 1e9 / static_cast<double>(tasks_.front().period_ns);
  h.loop_count = loop_count_;
  h.overruns = overruns_;
  h.jitter_p50_us = jitter_.percentile_us(50);
  h.jitter_p99_us = jitter_.percentile_us(99);
  h.jitter_max_us = jitter_.max_us();
  h.latency_count = latency_.count();
  h.latency_p50_us = latency_.percentile_us(50);
  h.latency_p99_us = latency_.percentile_us(99);
  h.latency_max_us = latency_.max_us();
  const double window_s = std::max(1e-9, static_cast<double>(h.window_us) / 1e6);
  for (const auto& [channel, s] : bus_.stats()) {
    h.channel.push_back(channel);
    h.count.push_back(s.received);
    h.rate_hz.push_back(static_cast<double>(s.received) / window_s);
    const auto it = expected_hz_.find(channel);
    h.expected_hz.push_back(it == expected_hz_.end() ? 0.0 : it->second);
    h.drops.push_back(s.drops);
    h.late.push_back(s.late);
  }
  h.num_channels = static_cast<int32_t>(h.channel.size());
  bus_.publish(contract::channels::kTimingHealth, h);
  next_health_us_ = now + 1000000;
}

void ProcessNode::housekeeping() {
  const int64_t now = wall_us();
  if (now >= next_heartbeat_us_) publish_heartbeat(hb_state_);
  if (started_ && now >= next_health_us_) publish_timing_health();
  for (const auto& fn : housekeeping_hooks_) fn();
  if (stop_requested_) stop_ = true;
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
  while (!started_ && !stop_) {
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

void ProcessNode::subscribe_lockstep_side() {
  // The master listens for acknowledgements, participants for the clock; each subscribes
  // only to its own side, so that nobody wakes up for its own messages.
  if (lockstep_side_subscribed_) return;
  lockstep_side_subscribed_ = true;
  if (master_) {
    bus_.subscribe<step_ack_t>(
      contract::channels::kStepAck,
      [this](const step_ack_t& ack) {
        schedule_.acknowledge(ack.process, ack.step, ack.next_due_ns);  // others are not of this run
      },
      100000);
  } else {
    bus_.subscribe<rig_clock_t>(
      contract::channels::kRigClock, [this](const rig_clock_t& tick) { on_rig_clock(tick); }, 100000);
  }
}

int ProcessNode::run() {
  if (inprocess() && !master_) throw std::logic_error("in process only the lockstep master runs; see join_inprocess()");
  subscribe_lockstep_side();
  if (!wait_for_start()) {
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
      if (t.timed() && t.next_ns < duration_ns_ && (task == nullptr || t.deadline_ns() < task->deadline_ns())) task = &t;
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

void ProcessNode::on_rig_clock(const rig_clock_t& tick) {
  if (!started_) {
    has_pending_tick_ = true;
    pending_tick_ = tick;
    return;
  }
  if (clock_mode_ != run_control_t::CLOCK_MODE_LOCKSTEP || master_) return;
  bool ran = false;
  for (auto& t : tasks_) {
    while (t.next_ns <= tick.sim_time_ns && t.next_ns < duration_ns_) {
      sim_time_ns_ = t.next_ns;
      t.fn(t.next_ns);
      t.next_ns += t.period_ns;
      ++loop_count_;
      ran = true;
    }
  }
  if (!ran) {
    // The master sent this tick again: our acknowledgement did not reach it.
    if (tick.step == last_acked_step_ && !ack_held_) publish_ack(tick.step, tick.utime);
    return;
  }
  if (ack_hold_requested_) {
    ack_hold_requested_ = false;
    ack_held_ = true;
    held_step_ = tick.step;
    held_utime_ = tick.utime;
    return;
  }
  publish_ack(tick.step, tick.utime);
  run_deferred();
}

int ProcessNode::run_lockstep_participant() {
  // Tasks run inside the RIG_CLOCK handler; wall time here only paces housekeeping.
  while (!stop_) {
    const int64_t before = monotonic_ns();
    wait_io(50000000);
    jitter_.add_ns(monotonic_ns() - before);
    housekeeping();
    if (next_due_ns() == kNever && hb_state_ != heartbeat_t::STATE_FINISHED) {
      publish_heartbeat(heartbeat_t::STATE_FINISHED);
    }
  }
  return kExitOk;
}

int ProcessNode::ack_missing(const std::string& participant, int64_t step, int64_t t, const std::string& when) {
  fault(fault_event_t::SEVERITY_FATAL, fault_event_t::CODE_STEP_ACK_TIMEOUT, contract::channels::kStepAck,
        "lockstep: no STEP_ACK from '" + participant + "' for step " + std::to_string(step) + " (t = " +
            std::to_string(static_cast<double>(t) / 1e9) + " s) " + when);
  return kExitAckTimeout;
}

int ProcessNode::run_lockstep_master() {
  if (tasks_.size() != 1) throw std::logic_error("the lockstep master needs exactly one task");
  Task& task = tasks_.front();
  for (const auto& p : participants_) {
    if (p != name_) {
      schedule_.add(p);
    }
  }
  for (int64_t step = 0; !stop_; ++step) {
    const int64_t t = step * task.period_ns;
    if (t > duration_ns_) break;
    const int64_t step_start = monotonic_ns();
    sim_time_ns_ = t;
    task.fn(t);
    task.next_ns = t + task.period_ns;
    ++loop_count_;

    if (!schedule_.tick_at(t)) {
      run_deferred();
      housekeeping();
      continue;  // nobody needs this step: no tick, no wait
    }
    rig_clock_t tick;
    tick.utime = t / 1000;
    tick.seq = clock_seq_++;
    tick.step = step;
    tick.sim_time_ns = t;
    tick.dt_ns = task.period_ns;
    tick.run_id = run_id_;
    bus_.publish(contract::channels::kRigClock, tick);
    run_deferred();  // outputs nobody waits for this step go out after the tick

    if (inprocess()) {
      // Delivering what the hub holds runs every due participant's tick to its
      // acknowledgement: nothing to wait for, and a missing one will never come.
      bus_.drain();
      const std::string missing = schedule_.missing(step, t);
      if (!missing.empty()) return ack_missing(missing, step, t, "in process, with nothing left to deliver");
      jitter_.add_ns(monotonic_ns() - step_start);
      housekeeping();
      continue;
    }
    // Wait for every participant due at this step. The tick goes out again every
    // kTickResendMs while an acknowledgement is missing: a participant that had not yet seen
    // RUN_CONTROL start, or whose acknowledgement was lost, answers the repeat (it runs nothing
    // twice); a stalled participant still times out.
    constexpr int64_t kTickResendMs = 250;
    const int64_t give_up = monotonic_ns() + static_cast<int64_t>(ack_timeout_ms_) * 1000000LL;
    int64_t resend_at = monotonic_ns() + kTickResendMs * 1000000LL;
    for (;;) {
      const std::string missing = schedule_.missing(step, t);
      if (missing.empty()) break;
      const int64_t left_ms = (give_up - monotonic_ns()) / 1000000LL;
      if (left_ms <= 0 || stop_) {
        if (stop_) return kExitOk;
        return ack_missing(missing, step, t, "within " + std::to_string(ack_timeout_ms_) + " ms");
      }
      wait_io(std::min<int64_t>(left_ms, 50) * 1000000LL);
      housekeeping();
      if (monotonic_ns() >= resend_at) {
        bus_.publish(contract::channels::kRigClock, tick);
        resend_at = monotonic_ns() + kTickResendMs * 1000000LL;
      }
    }
    jitter_.add_ns(monotonic_ns() - step_start);  // lockstep: wall time per step
    housekeeping();
  }
  if (!stop_) idle_until_stopped();
  return kExitOk;
}

}  // namespace nimble::transport
