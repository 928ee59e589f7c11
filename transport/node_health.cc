// ProcessNode (transport/node.h), part: what a process says about itself: FAULT events (rate-limited per
// code), the injected faults it applies to what it publishes, HEARTBEAT and TIMING_HEALTH.

#include "transport/node.h"

#include "contract/messages.h"

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
#include <memory>
#include <stdexcept>
#include <utility>

#include <nimble/rig_clock_t.hpp>
#include <nimble/timing_health_t.hpp>

namespace nimble::transport {

void ProcessNode::fault(int8_t severity, int32_t code, const std::string& channel, const std::string& message,
                        int64_t rig_utime_us) {
  const int64_t second = monotonic_ns() / 1000000000LL;
  auto& [sec, count] = fault_budget_[code];
  if (sec != second) {
    sec = second;
    count = 0;
  }
  if (++count > 10) return;
  FaultEvent f;
  f.utime = wall_us();
  f.seq = fault_seq_++;
  f.rig_utime = rig_utime_us >= 0 ? rig_utime_us : sim_time_ns_ / 1000;
  f.process = name_;
  f.severity = severity;
  f.code = code;
  f.channel = channel;
  f.message = message;
  bus_.publish(contract::channels::kFault, contract::to_message(f));
}

void ProcessNode::inject_faults(const std::vector<contract::FaultSpec>& faults, uint64_t seed) {
  bool any = false;
  for (const auto& f : faults) any |= f.target != contract::kFaultTargetCan;
  if (!any) return;
  bus_.set_fault_injector(
      std::make_unique<FaultInjector>(faults, seed, [this](const contract::FaultSpec& f, bool began, int64_t utime) {
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

int ProcessNode::add_stage(const std::string& name) {
  stages_.emplace_back(name, nullptr);
  return static_cast<int>(stages_.size() - 1);
}

void ProcessNode::record_stage_ns(int stage, int64_t ns) {
  std::unique_ptr<LatencyHistogram>& histogram = stages_[static_cast<std::size_t>(stage)].second;
  if (!histogram) histogram = std::make_unique<LatencyHistogram>();
  histogram->add_ns(ns);
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
  for (const auto& [stage, histogram] : stages_) {
    if (!histogram) continue;
    h.stage.push_back(stage);
    h.stage_count.push_back(histogram->count());
    h.stage_p50_us.push_back(histogram->percentile_us(50));
    h.stage_p99_us.push_back(histogram->percentile_us(99));
    h.stage_max_us.push_back(histogram->max_us());
  }
  h.num_stages = static_cast<int32_t>(h.stage.size());
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

}  // namespace nimble::transport
