// ProcessNode (transport/node.h), part: the lockstep clock: a participant runs the tasks due at each
// RIG_CLOCK tick and answers STEP_ACK; the master (the plant) runs its step, publishes RIG_CLOCK
// and waits for every due participant.

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
          if (ack.step == tick_step_) {
            const auto it = turnaround_stage_.find(ack.process);
            if (it != turnaround_stage_.end()) record_stage_ns(it->second, monotonic_ns() - tick_sent_ns_);
          }
        },
        100000);
  } else {
    bus_.subscribe<rig_clock_t>(
        contract::channels::kRigClock, [this](const rig_clock_t& tick) { on_rig_clock(tick); }, 100000);
  }
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
        "lockstep: no STEP_ACK from '" + participant + "' for step " + std::to_string(step) +
            " (t = " + std::to_string(static_cast<double>(t) / 1e9) + " s) " + when);
  return kExitAckTimeout;
}

int ProcessNode::run_lockstep_master() {
  if (tasks_.size() != 1) throw std::logic_error("the lockstep master needs exactly one task");
  Task& task = tasks_.front();
  for (const auto& p : participants_) {
    if (p != name_) {
      schedule_.add(p);
      // Over LCM: each participant's turnaround, from the tick going out to its acknowledgement
      // coming in (its decode, its step, its publications, the transport both ways).
      if (!inprocess()) {
        turnaround_stage_[p] = add_stage("lockstep: " + p + "'s turnaround, RIG_CLOCK sent to its STEP_ACK received");
      }
    }
  }
  const int own_step_stage = inprocess() ? -1 : add_stage("lockstep: " + name_ + "'s own step");
  for (int64_t step = 0; !stop_; ++step) {
    const int64_t t = step * task.period_ns;
    if (t > duration_ns_) break;
    const int64_t step_start = monotonic_ns();
    sim_time_ns_ = t;
    task.fn(t);
    if (own_step_stage >= 0) record_stage_ns(own_step_stage, monotonic_ns() - step_start);
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
    tick_sent_ns_ = monotonic_ns();
    tick_step_ = step;
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
