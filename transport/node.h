#pragma once
/// ProcessNode: the run-time frame every rig process shares.
///
/// A process registers periodic tasks (in simulated time) and message handlers, then
/// calls run(). ProcessNode then
///  - publishes HEARTBEAT (READY at 10 Hz until the run starts, then 2 Hz), FAULT events
///    (rate-limited per code) and TIMING_HEALTH (1 Hz, cumulative loop statistics);
///  - waits for RUN_CONTROL COMMAND_START from the launcher;
///  - real time: runs each task against absolute deadlines of CLOCK_MONOTONIC from the
///    run's t0, handling messages while it waits (ppoll on the LCM descriptor);
///  - lockstep participant: runs the tasks due at each RIG_CLOCK tick, then answers STEP_ACK
///    with the time it is next due;
///  - lockstep master (the plant): runs its task once per step, publishes RIG_CLOCK, and
///    starts the next step only when every due participant has acknowledged; a participant
///    that does not answer within the ack timeout is named in a FAULT and run() returns
///    kExitAckTimeout;
///  - stops on RUN_CONTROL COMMAND_STOP, SIGTERM or SIGINT, after the duration it reports
///    STATE_FINISHED and idles until stopped.
///
/// Channels: publishes HEARTBEAT, FAULT, TIMING_HEALTH, STEP_ACK (lockstep participants),
/// RIG_CLOCK (lockstep master); subscribes RUN_CONTROL, RIG_CLOCK (participants),
/// STEP_ACK (master).

#include <csignal>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nimble/fault_event_t.hpp>
#include <nimble/heartbeat_t.hpp>
#include <nimble/rig_clock_t.hpp>
#include <nimble/run_control_t.hpp>
#include <nimble/step_ack_t.hpp>

#include "contract/channels.h"
#include "contract/lockstep_schedule.h"
#include "transport/bus.h"
#include "transport/clock.h"
#include "transport/inprocess_hub.h"
#include "transport/process_options.h"

namespace nimble::transport {

class ProcessNode {
 public:
  /// A task run every `period_ns` of simulated time, first at t = 0.
  using TaskFn = std::function<void(int64_t sim_time_ns)>;

  /// What starts a task in real time. In lockstep every task runs on the RIG_CLOCK tick.
  enum class Trigger {
    kTimer,  ///< at its deadline on CLOCK_MONOTONIC
    kInput,  ///< when an input arrives whose time has reached the task's next due time
             ///< (notify_input); the onboard loop of the vehicle is triggered by its IMU
  };

  ProcessNode(std::string name, const std::string& lcm_url, std::string config_digest = "");
  /// Over LCM at `options.lcm_url`, or through `options.hub` in an in-process run.
  explicit ProcessNode(const NodeOptions& options, std::string config_digest = "");
  /// The same, run with `realtime`.
  ProcessNode(const NodeOptions& options, const RealtimeSettings& realtime, std::string config_digest = "");

  /// True in an in-process run (see "In process" below).
  bool inprocess() const { return bus_.hub() != nullptr; }

  Bus& bus() { return bus_; }
  const std::string& name() const { return name_; }

  /// Registers a periodic task. `rate_hz` must make an integer period in ns.
  /// An input-triggered task with `backstop_ns` > 0 also runs, in real time, when its input is
  /// that late: at t0 + its due time + backstop_ns (so a lost input stream cannot stop the loop
  /// that must notice it).
  /// @throws std::invalid_argument otherwise.
  void add_task(const std::string& label, double rate_hz, TaskFn fn, Trigger trigger = Trigger::kTimer,
                int64_t backstop_ns = 0);

  /// Real time: an input stamped `input_sim_time_ns` arrived; runs the input-triggered
  /// tasks that are due. No effect in lockstep or before the start.
  void notify_input(int64_t input_sim_time_ns);

  /// Runs `fn` once the current task has finished and, in lockstep, after its STEP_ACK has
  /// gone out: for outputs nobody in the loop waits for (status, set-point records).
  void defer(std::function<void()> fn) { deferred_.push_back(std::move(fn)); }

  /// Also waits on descriptor `fd` wherever the node waits for messages (before the start,
  /// in real time, in lockstep, after the run): `on_readable` runs when it is readable. For
  /// a second input next to LCM, such as a CAN socket.
  void watch_fd(int fd, std::function<void()> on_readable);

  /// Runs `fn` at every housekeeping pass (several times per second of wall time, whatever
  /// the clock): for periodic reports such as link health.
  void on_housekeeping(std::function<void()> fn) { housekeeping_hooks_.push_back(std::move(fn)); }

  /// Lockstep participant, from a task: this tick's STEP_ACK waits until release_ack(). For
  /// a process whose output for the tick depends on an input still in flight (the CAN bridge
  /// acknowledges a control cycle once that cycle's command has crossed the bus). The master
  /// names the process if the release does not come within its ack timeout.
  void hold_ack() { ack_hold_requested_ = true; }
  /// Sends the held STEP_ACK, then the deferred outputs. No effect if nothing is held.
  void release_ack();
  /// True while a STEP_ACK is held.
  bool ack_held() const { return ack_held_ || ack_hold_requested_; }

  /// Records one control-loop latency [ns] (reported on TIMING_HEALTH).
  void record_latency_ns(int64_t ns) { latency_.add_ns(ns); }

  /// The control loop's stages this process times (reported on TIMING_HEALTH, read by the
  /// latency budget of bench_rig): add_stage() names one and returns its index for
  /// record_stage_ns(). The loop's stages are timed in real time only (stage_timing()); the
  /// lockstep master times each participant's turnaround and its own step over LCM.
  /// A stage's histogram is made at its first sample: a run that times none (in process) does
  /// not pay for it.
  int add_stage(const std::string& name);
  void record_stage_ns(int stage, int64_t ns);
  /// True when stages are timed: a real-time run, started (the wall clock and the rig's agree).
  bool stage_timing() const { return started_ && !lockstep() && !inprocess(); }
  /// Real time: the age at `now_ns` (CLOCK_MONOTONIC; default now) of a sample due at rig time
  /// `rig_utime` [us]: the wall time since t0_monotonic_ns() + rig_utime [ns].
  int64_t age_ns(int64_t rig_utime, int64_t now_ns = monotonic_ns()) const {
    return now_ns - (t0_ns_ + message_us_to_ns(rig_utime));
  }

  /// Makes this node the lockstep master (the plant): its single task defines the step.
  void set_lockstep_master(bool master) { master_ = master; }
  /// Lockstep master: how long to wait for a participant's STEP_ACK [ms] (wall clock).
  void set_ack_timeout_ms(int ms) { ack_timeout_ms_ = ms; }

  /// Real time: wake this long before each deadline and spin to it [ns] (0: sleep only).
  /// Trades CPU for wake-up jitter.
  void set_spin_ns(int64_t ns) { spin_ns_ = ns; }

  /// Expected receive rate of a channel [Hz], reported on TIMING_HEALTH: the run's own
  /// (Scenario::expected_rate(), from contract::expected_rates()); 0 if the run gives none.
  void set_expected_rate(const std::string& channel, double hz) { expected_hz_[channel] = hz; }

  /// Applies the scenario's `faults` to what this process publishes (transport/fault_injector.h):
  /// each fault's beginning and end is announced as a CODE_FAULT_INJECTED event. `seed` is the
  /// run's (the random choices of a fault are drawn from it).
  void inject_faults(const std::vector<contract::FaultSpec>& faults, uint64_t seed);

  /// Publishes a fault event (rate-limited to 10 per second per code). Never throws.
  /// `rig_utime_us` (>= 0) stamps it at that rig time instead of the current task's.
  void fault(int8_t severity, int32_t code, const std::string& channel, const std::string& message,
             int64_t rig_utime_us = -1);

  /// Real time: CLOCK_MONOTONIC time of simulated time 0 [ns] (valid once started).
  int64_t t0_monotonic_ns() const { return t0_ns_; }

  /// Current simulated time [ns] (the time of the task being run).
  int64_t sim_time_ns() const { return sim_time_ns_; }
  /// Clock mode of the run (run_control_t::CLOCK_MODE_*); valid once started.
  int8_t clock_mode() const { return clock_mode_; }
  bool lockstep() const { return clock_mode_ == run_control_t::CLOCK_MODE_LOCKSTEP; }

  /// Waits for the start, runs until stopped. Returns the process exit code.
  ///
  /// In process (the node's Bus is on an InprocessHub, one thread runs every node): only the
  /// lockstep master calls run(). Its waits deliver what the hub holds instead of blocking, a
  /// participant whose acknowledgement is still missing once nothing is left to deliver is a
  /// fatal fault at once, and it returns when the duration is flown. The participants call
  /// join_inprocess() before the start and finish_inprocess() after the master returns;
  /// their tasks run from the RIG_CLOCK ticks the hub delivers.
  int run();
  /// In process, a participant: subscribes to RIG_CLOCK and announces READY.
  void join_inprocess();
  /// In process, a participant: the last TIMING_HEALTH and HEARTBEAT STOPPING.
  void finish_inprocess();

  /// Requests a clean stop from a signal handler or a callback.
  static void request_stop() { stop_requested_ = 1; }
  /// Withdraws a stop request: a library that flies again after an interrupted flight (the
  /// Python module) starts the next one clean. The rig's commands never do: after Ctrl-C, what
  /// they would fly next stops too.
  static void clear_stop_request() { stop_requested_ = 0; }
  /// Ends this node's run at its next step, cleanly, as a stop request does (in process: the
  /// run's recorder could no longer write its log).
  void end_run() { stop_ = true; }
  /// Installs SIGTERM/SIGINT handlers that call request_stop().
  static void install_signal_handlers();

 private:
  struct Task {
    std::string label;
    int64_t period_ns;
    TaskFn fn;
    Trigger trigger = Trigger::kTimer;
    int64_t next_ns = 0;
    int64_t backstop_ns = 0;  ///< input-triggered: also runs this late on the timer (0: never)
    /// Real time: when it runs on the timer [ns after t0].
    int64_t deadline_ns() const { return next_ns + (trigger == Trigger::kInput ? backstop_ns : 0); }
    bool timed() const { return trigger == Trigger::kTimer || backstop_ns > 0; }
  };

  void subscribe_lockstep_side();
  void publish_heartbeat(int8_t state);
  void publish_timing_health();
  void housekeeping();
  bool wait_for_start();
  int run_realtime();
  int run_lockstep_participant();
  int run_lockstep_master();
  /// Lockstep master: the fatal fault naming `participant`, which did not acknowledge `step`
  /// (time `t`) `when`; returns kExitAckTimeout.
  int ack_missing(const std::string& participant, int64_t step, int64_t t, const std::string& when);

  void idle_until_stopped();
  /// Waits up to `timeout_ns` for LCM or a watched descriptor and handles what is ready
  /// (0: poll). Returns the number of descriptors that were ready.
  int wait_io(int64_t timeout_ns);
  void publish_ack(int64_t step, int64_t utime);
  void on_run_control(const run_control_t& msg);
  /// The simulated time at which the next task is due [ns]; kNever if none is.
  int64_t next_due_ns() const;
  static constexpr int64_t kNever = std::numeric_limits<int64_t>::max();

  std::string name_;
  std::string config_digest_;
  Bus bus_;
  int64_t late_threshold_ns_ = 0;
  std::vector<Task> tasks_;
  bool master_ = false;
  bool lockstep_side_subscribed_ = false;
  int ack_timeout_ms_ = 2000;
  std::map<std::string, double> expected_hz_;

  bool started_ = false;
  bool stop_ = false;
  int8_t clock_mode_ = run_control_t::CLOCK_MODE_REALTIME;
  int64_t t0_ns_ = 0;
  int64_t duration_ns_ = 0;
  std::string run_id_;
  std::vector<std::string> participants_;
  int64_t sim_time_ns_ = 0;

  int8_t hb_state_ = heartbeat_t::STATE_STARTING;
  int64_t hb_seq_ = 0, fault_seq_ = 0, health_seq_ = 0, ack_seq_ = 0, clock_seq_ = 0;
  int64_t next_heartbeat_us_ = 0;
  int64_t next_health_us_ = 0;
  int64_t started_wall_us_ = 0;
  std::map<int32_t, std::pair<int64_t, int>> fault_budget_;  // code -> (second, count)

  LatencyHistogram jitter_;
  LatencyHistogram latency_;
  std::vector<std::pair<std::string, std::unique_ptr<LatencyHistogram>>> stages_;  // null: no sample yet
  /// Lockstep master over LCM: each participant's turnaround stage, and the tick being waited for.
  std::map<std::string, int> turnaround_stage_;
  int64_t tick_sent_ns_ = 0, tick_step_ = -1;
  std::vector<std::function<void()>> deferred_;
  struct Watched {
    int fd;
    std::function<void()> on_readable;
  };
  std::vector<Watched> watched_;
  std::vector<std::function<void()>> housekeeping_hooks_;
  bool ack_hold_requested_ = false;
  bool ack_held_ = false;
  int64_t held_step_ = 0, held_utime_ = 0;
  /// Lockstep participant: runs the tasks due at `tick` and acknowledges it. A tick that comes
  /// before RUN_CONTROL start is kept (pending_tick_) and handled once the run starts; a tick
  /// already acknowledged (the master sends it again when no acknowledgement came) is
  /// acknowledged again without running anything.
  void on_rig_clock(const rig_clock_t& tick);
  bool has_pending_tick_ = false;
  rig_clock_t pending_tick_{};
  int64_t last_acked_step_ = -1;
  void run_deferred();
  int64_t spin_ns_ = 0;
  int64_t start_wait_ns_ = 0;  ///< give up waiting for the start after this long (0: never)
  bool start_wait_expired_ = false;
  int64_t loop_count_ = 0;
  int64_t overruns_ = 0;

  // Lockstep master state: participant -> next due time [ns].
  contract::LockstepSchedule schedule_;

  static volatile std::sig_atomic_t stop_requested_;
};

}  // namespace nimble::transport
