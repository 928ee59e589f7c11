#include "launcher/recorder.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include <nimble/rig_clock_t.hpp>
#include <nimble/truth_state_t.hpp>

#include "contract/channels.h"
#include "contract/decode.h"
#include "contract/rates.h"
#include "lcmjson/lcm_json.h"
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

int64_t expected_log_bytes(const RunPlan& plan) {
  constexpr int kEventHeader = 4 + 8 + 8 + 4 + 4;  // sync, event number, timestamp, two lengths
  double per_s = 0.0;
  for (const auto& [channel, hz] : monitor_config(plan).expected_hz) {
    const lcmjson::LcmStruct* type = lcmjson::rig_type_for_channel(channel);
    const int message = type != nullptr ? lcmjson::typical_encoded_size(*type) : 64;
    per_s += hz * static_cast<double>(kEventHeader + static_cast<int>(channel.size()) + message);
  }
  return static_cast<int64_t>(std::ceil(per_s * plan.scenario.duration_s));
}

std::string log_space_problem(const RunPlan& plan, const std::string& log_file, int64_t max_bytes, bool check_free) {
  const int64_t expected = expected_log_bytes(plan);
  char duration[32];
  std::snprintf(duration, sizeof duration, "%.1f", plan.scenario.duration_s);
  const std::string need = "the log " + log_file + " is expected to take " + human_bytes(expected) + " (" +
                           std::to_string(expected) + " bytes for " + duration + " s simulated)";
  if (max_bytes > 0 && expected > max_bytes) {
    return need + ", over its limit --log-max-bytes " + std::to_string(max_bytes) +
           "; raise the limit or shorten the run (duration_s)";
  }
  if (!check_free) return "";
  const int64_t free = free_bytes_at(log_file);
  const int64_t wanted = max_bytes > 0 ? std::min(expected, max_bytes) : expected;
  if (free >= 0 && wanted > free) {
    return need + ", but its filesystem has " + human_bytes(free) + " (" + std::to_string(free) +
           " bytes) free; free some space, log elsewhere (--log), bound the log (--log-max-bytes) or fly anyway "
           "(--no-space-check: the run then ends, named, when the disk is full)";
  }
  return "";
}

Recorder::Recorder(const std::string& log_file, RunMonitor& monitor, LogStamps stamps)
    : file_(log_file), monitor_(monitor), log_(log_file, kWriteBuffer, "the log"), stamps_(stamps) {
  last_flush_ns_ = transport::monotonic_ns();
  wall_minus_monotonic_us_ = transport::wall_us() - last_flush_ns_ / 1000;
}

Recorder::~Recorder() {
  if (!failed()) checked([this] { log_.flush(); });
}

int64_t Recorder::stamp_us(const std::string& channel, const void* data, int size, int64_t recv_ns) {
  if (stamps_ == LogStamps::kWallClock) return transport::wall_us();
  if (channel == contract::channels::kRigClock) {
    rig_clock_t tick{};
    if (contract::decode_exact(data, size, tick)) {
      if (sim_base_us_ < 0) place_simulated_time(tick.sim_time_ns / 1000, recv_ns);
      last_stamp_us_ = std::max(last_stamp_us_, sim_base_us_ + tick.sim_time_ns / 1000);
      return last_stamp_us_;
    }
  }
  if (sim_base_us_ < 0 && channel == contract::channels::kTruth) {
    // The master's first step goes out before its tick: its truth places simulated time.
    truth_state_t truth{};
    if (contract::decode_exact(data, size, truth) && truth.step >= 0) {
      place_simulated_time(truth.utime, recv_ns);
      last_stamp_us_ = std::max(last_stamp_us_, sim_base_us_ + truth.utime);
      return last_stamp_us_;
    }
  }
  if (sim_base_us_ < 0) last_stamp_us_ = std::max(last_stamp_us_, received_wall_us(recv_ns));
  return last_stamp_us_;
}

int64_t Recorder::received_wall_us(int64_t recv_ns) const {
  return recv_ns > 0 ? wall_minus_monotonic_us_ + recv_ns / 1000 : transport::wall_us();
}

void Recorder::place_simulated_time(int64_t sim_utime, int64_t recv_ns) {
  // The wall clock of the message's receipt, not of its recording: a recorder that falls behind
  // does not move the run's simulated time.
  sim_base_us_ = std::max(received_wall_us(recv_ns), last_stamp_us_) - sim_utime;
}

template <typename Write>
void Recorder::checked(Write&& write) {
  try {
    write();
  } catch (const OutputError& e) {
    const int64_t at = e.offset() >= 0 ? e.offset() : log_.size();
    const std::string why = e.error_number() != 0 ? std::strerror(e.error_number()) : std::string(e.what());
    failure_ = "log write failed at byte " + std::to_string(at) + " of " + file_ + ": " + why;
  }
}

namespace {
/// Appends `v` big-endian (the LCM log's byte order).
template <typename T>
void put_be(std::string& out, T v) {
  for (int i = static_cast<int>(sizeof(T)) - 1; i >= 0; --i) {
    out.push_back(static_cast<char>((static_cast<uint64_t>(v) >> (8 * i)) & 0xFF));
  }
}
constexpr uint32_t kLcmLogSync = 0xEDA1DA01u;  ///< every event's first word (lcm_eventlog.c)
}  // namespace

void Recorder::record(const std::string& channel, const void* data, int size, int64_t recv_ns, bool own_encoding) {
  if (!failed()) {
    // One event of the LCM log format: sync word, event number, timestamp [us], channel
    // length, data length (big-endian), the channel's name, the data.
    header_.clear();
    put_be<uint32_t>(header_, kLcmLogSync);
    put_be<int64_t>(header_, event_number_);
    put_be<int64_t>(header_, stamp_us(channel, data, size, recv_ns));
    put_be<int32_t>(header_, static_cast<int32_t>(channel.size()));
    put_be<int32_t>(header_, size);
    header_ += channel;
    checked([&] {
      log_.append(header_.data(), header_.size());
      log_.append(data, static_cast<std::size_t>(size));
      log_.end_record();
    });
    ++event_number_;
  }
  monitor_.on_message(channel, data, size, recv_ns, own_encoding);
  if (!failed()) {
    pending_sim_s_.push_back(monitor_.sim_time_s());
    // Events in the file no longer need their time, but the newest of them.
    if (pending_sim_s_.size() >= 4096) forget_kept();
  }
}

void Recorder::forget_kept() {
  const int64_t kept = log_.kept_records();
  if (kept <= pending_first_) return;
  const auto n =
      static_cast<std::size_t>(std::min<int64_t>(kept - pending_first_, static_cast<int64_t>(pending_sim_s_.size())));
  kept_sim_s_ = pending_sim_s_[n - 1];
  pending_sim_s_.erase(pending_sim_s_.begin(), pending_sim_s_.begin() + static_cast<std::ptrdiff_t>(n));
  pending_first_ += static_cast<int64_t>(n);
}

void Recorder::flush_if_due(int64_t now_ns, int64_t flush_period_ns) {
  if (now_ns - last_flush_ns_ < flush_period_ns) return;
  flush();
  last_flush_ns_ = now_ns;
}

void Recorder::flush() {
  if (failed()) return;
  checked([this] { log_.flush(); });
  forget_kept();
}

void Recorder::close() {
  if (failed()) return;
  checked([this] { log_.close(); });
  forget_kept();
}

LogKept Recorder::kept() const {
  LogKept k;
  k.file = file_;
  k.events = log_.kept_records();
  k.bytes = log_.kept_bytes();
  k.sim_time_s = kept_sim_s_;
  const int64_t known = std::min<int64_t>(k.events - pending_first_, static_cast<int64_t>(pending_sim_s_.size()));
  if (known > 0) k.sim_time_s = pending_sim_s_[static_cast<std::size_t>(known - 1)];
  k.failure = failure_;
  return k;
}

}  // namespace nimble::launcher
