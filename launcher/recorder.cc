#include "launcher/recorder.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <nimble/rig_clock_t.hpp>

#include "contract/channels.h"
#include "contract/decode.h"
#include "contract/rates.h"
#include "transport/clock.h"

namespace nimble::launcher {

namespace {
constexpr std::size_t kWriteBuffer = 1 << 20;
}

MonitorConfig monitor_config(const RunPlan& plan) {
  MonitorConfig mc;
  mc.lockstep = plan.lockstep();
  mc.late_threshold_us = process_run_options(plan.scenario).late_threshold_us;
  // In process the recorder is no lockstep participant: nothing it does can fall behind.
  const double logger_period_ms = plan.inprocess() ? 0.0 : plan.logger_period_ms;
  mc.expected_hz = contract::expected_rates(
      plan.rates, contract::RunShape{plan.lockstep(), logger_period_ms, plan.scenario.processes.size()});
  mc.wall_clock_channels = contract::wall_clock_channels();
  mc.processes = plan.scenario.processes;
  if (plan.judge.trace_hz > 0) mc.trace_interval_us = std::llround(1e6 / plan.judge.trace_hz);
  return mc;
}

Recorder::Recorder(const std::string& log_file, RunMonitor& monitor, LogStamps stamps)
    : file_(log_file), monitor_(monitor), log_(std::make_unique<lcm::LogFile>(log_file, "w")), stamps_(stamps) {
  if (!log_->good()) throw std::runtime_error("cannot open log " + log_file + " for writing");
  buffer_ = std::make_unique<char[]>(kWriteBuffer);
  std::setvbuf(log_->getFilePtr(), buffer_.get(), _IOFBF, kWriteBuffer);
  last_flush_ns_ = transport::monotonic_ns();
}

Recorder::~Recorder() {
  flush();
  log_.reset();  // closes the file before the buffer goes
}

int64_t Recorder::stamp_us(const std::string& channel, const void* data, int size) {
  if (stamps_ == LogStamps::kWallClock) return transport::wall_us();
  if (channel == contract::channels::kRigClock) {
    rig_clock_t tick{};
    if (contract::decode_exact(data, size, tick)) {
      if (sim_base_us_ < 0) sim_base_us_ = transport::wall_us() - tick.sim_time_ns / 1000;
      last_stamp_us_ = std::max(last_stamp_us_, sim_base_us_ + tick.sim_time_ns / 1000);
      return last_stamp_us_;
    }
  }
  if (sim_base_us_ < 0) last_stamp_us_ = std::max(last_stamp_us_, transport::wall_us());
  return last_stamp_us_;
}

void Recorder::record(const std::string& channel, const void* data, int size, int64_t recv_ns, bool own_encoding) {
  lcm::LogEvent ev;
  ev.eventnum = event_number_++;
  ev.timestamp = stamp_us(channel, data, size);
  ev.channel = channel;
  ev.datalen = size;
  ev.data = const_cast<void*>(data);
  log_->writeEvent(&ev);
  monitor_.on_message(channel, data, size, recv_ns, own_encoding);
}

void Recorder::flush_if_due(int64_t now_ns, int64_t flush_period_ns) {
  if (now_ns - last_flush_ns_ < flush_period_ns) return;
  flush();
  last_flush_ns_ = now_ns;
}

void Recorder::flush() { std::fflush(log_->getFilePtr()); }

}  // namespace nimble::launcher
