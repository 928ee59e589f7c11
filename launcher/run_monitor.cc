#include "launcher/run_monitor.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <cstdio>

#include <nimble/estimator_state_t.hpp>
#include <nimble/fault_event_t.hpp>
#include <nimble/heartbeat_t.hpp>
#include <nimble/mocap_pose_t.hpp>
#include <nimble/step_ack_t.hpp>
#include <nimble/timing_health_t.hpp>
#include <nimble/truth_state_t.hpp>

#include "contract/channels.h"

namespace nimble::launcher {
namespace {

using namespace contract::channels;

/// Reads a big-endian int64 at `offset` of an encoded LCM message.
bool read_i64(const void* data, int size, int offset, int64_t& out) {
  if (size < offset + 8) return false;
  const auto* b = static_cast<const uint8_t*>(data) + offset;
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v = (v << 8) | b[i];
  out = static_cast<int64_t>(v);
  return true;
}

template <typename T>
bool decode(const void* data, int size, T& msg) {
  return msg.decode(data, 0, size) == size;
}

}  // namespace

void RunMonitor::count_seq(Counter& c, const std::string& publisher, int64_t seq) {
  auto it = c.last_seq.find(publisher);
  if (it != c.last_seq.end() && seq > it->second + 1) c.drops += seq - it->second - 1;
  c.last_seq[publisher] = seq;
}

void RunMonitor::on_message(const std::string& channel, const void* data, int size, int64_t recv_ns) {
  Counter& c = counters_[channel];
  ++c.count;

  if (channel == kHeartbeat) {
    heartbeat_t hb{};
    if (!decode(data, size, hb)) { ++c.malformed; return; }
    heartbeat_[hb.process] = hb.state;
    count_seq(c, hb.process, hb.seq);
    return;
  }
  if (channel == kTimingHealth) {
    timing_health_t h{};
    if (!decode(data, size, h)) { ++c.malformed; return; }
    TimingSummary& t = timing_[h.process];
    t.loop_rate_hz = h.loop_rate_hz;
    t.loop_count = h.loop_count;
    t.overruns = h.overruns;
    t.jitter_p50_us = h.jitter_p50_us;
    t.jitter_p99_us = h.jitter_p99_us;
    t.jitter_max_us = h.jitter_max_us;
    t.latency_count = h.latency_count;
    t.latency_p50_us = h.latency_p50_us;
    t.latency_p99_us = h.latency_p99_us;
    t.latency_max_us = h.latency_max_us;
    for (int i = 0; i < h.num_channels; ++i) {
      t.received[h.channel[static_cast<std::size_t>(i)]] =
          TimingSummary::Received{h.count[static_cast<std::size_t>(i)], h.late[static_cast<std::size_t>(i)]};
    }
    count_seq(c, h.process, h.seq);
    return;
  }
  if (channel == kCanHealth) {
    can_health_t h{};
    if (!decode(data, size, h)) { ++c.malformed; return; }
    can_health_[h.process] = h;
    count_seq(c, h.process, h.seq);
    return;
  }
  if (channel == kFault) {
    fault_event_t f{};
    if (!decode(data, size, f)) { ++c.malformed; return; }
    faults_.push_back(FaultRecord{f.process, f.severity, f.code, f.channel, f.message,
                                  static_cast<double>(f.rig_utime) / 1e6});
    count_seq(c, f.process, f.seq);
    return;
  }
  if (channel == kStepAck) {
    step_ack_t a{};
    if (!decode(data, size, a)) { ++c.malformed; return; }
    count_seq(c, a.process, a.seq);
    return;
  }

  // Stream channels: one publisher, utime and seq at byte offsets 8 and 16.
  int64_t utime = 0, seq = 0;
  if (!read_i64(data, size, 8, utime) || !read_i64(data, size, 16, seq)) {
    ++c.malformed;
    return;
  }
  count_seq(c, "", seq);
  // A message is due at its utime; a pose is stamped at mid-exposure and due latency_us later.
  int64_t due_us = utime;
  if (channel == kMocapPose) {
    mocap_pose_t pose{};
    if (!decode(data, size, pose)) { ++c.malformed; return; }
    due_us += pose.latency_us;
  }
  if (!cfg_.lockstep && cfg_.t0_monotonic_ns > 0 && channel != kRunControl) {
    const int64_t lag_us = (recv_ns - cfg_.t0_monotonic_ns) / 1000 - due_us;
    if (lag_us > cfg_.late_threshold_us) ++c.late;
  }
  if (channel == kTruth) {
    truth_state_t t{};
    if (!decode(data, size, t)) { ++c.malformed; return; }
    const double p = t.omega_body_radps[0], v = t.velocity_body_mps[1], phi = t.euler_rad[0];
    FlightSummary& f = flight_;
    if (!std::isfinite(p) || !std::isfinite(v) || !std::isfinite(phi) || !std::isfinite(t.euler_rad[1])) f.finite = false;
    if (f.samples == 0) {
      f.min_p = f.max_p = p;
      f.min_v = f.max_v = v;
      f.min_phi = f.max_phi = phi;
      f.min_df = f.max_df = t.delta_f_radps;
    }
    ++f.samples;
    f.max_abs_p = std::max(f.max_abs_p, std::fabs(p));
    f.max_abs_v = std::max(f.max_abs_v, std::fabs(v));
    f.max_abs_phi = std::max(f.max_abs_phi, std::fabs(phi));
    f.max_abs_theta = std::max(f.max_abs_theta, std::fabs(t.euler_rad[1]));
    f.min_p = std::min(f.min_p, p); f.max_p = std::max(f.max_p, p);
    f.min_v = std::min(f.min_v, v); f.max_v = std::max(f.max_v, v);
    f.min_phi = std::min(f.min_phi, phi); f.max_phi = std::max(f.max_phi, phi);
    f.min_df = std::min(f.min_df, t.delta_f_radps); f.max_df = std::max(f.max_df, t.delta_f_radps);
    f.final_p = p;
    f.final_v = v;
    f.final_phi = phi;
    f.last_sim_time_s = static_cast<double>(t.utime) / 1e6;
    recent_truth_[t.utime] = TruthPoint{phi, p, v};
    while (!recent_truth_.empty() && recent_truth_.begin()->first < t.utime - 1000000) {
      recent_truth_.erase(recent_truth_.begin());
    }
  }
  if (channel == kEstimate) {
    estimator_state_t e{};
    if (!decode(data, size, e)) { ++c.malformed; return; }
    est_.poses_accepted = e.poses_accepted;
    est_.poses_rejected = e.poses_rejected;
    est_.poses_missing = e.poses_missing;
    est_.poses_too_old = e.poses_too_old;
    est_.poses_too_new = e.poses_too_new;
    est_.velocity_windows_uncovered = e.velocity_windows_uncovered;
    est_.imu_rejected = e.imu_rejected;
    est_.imu_gaps = e.imu_gaps;
    const auto it = recent_truth_.find(e.imu_utime);
    if (it == recent_truth_.end()) return;
    const double dphi = (e.euler_rad[0] - it->second.phi) * 180.0 / M_PI;
    est_phi2_ += dphi * dphi;
    est_p2_ += std::pow(e.omega_body_radps[0] - it->second.p, 2);
    est_v2_ += std::pow(e.velocity_body_mps[1] - it->second.v, 2);
    est_.phi_max_deg = std::max(est_.phi_max_deg, std::fabs(dphi));
    ++est_.samples;
  }
}

EstimatorSummary RunMonitor::estimator() const {
  EstimatorSummary s = est_;
  if (s.samples > 0) {
    const double n = static_cast<double>(s.samples);
    s.phi_rms_deg = std::sqrt(est_phi2_ / n);
    s.p_rms_radps = std::sqrt(est_p2_ / n);
    s.v_rms_mps = std::sqrt(est_v2_ / n);
  }
  return s;
}

int RunMonitor::heartbeat_state(const std::string& process) const {
  const auto it = heartbeat_.find(process);
  return it == heartbeat_.end() ? -1 : it->second;
}

std::map<std::string, ChannelSummary> RunMonitor::channels(double sim_duration_s, double wall_duration_s) const {
  std::map<std::string, ChannelSummary> out;
  for (const auto& [name, hz] : cfg_.expected_hz) out[name].expected_hz = hz;
  for (const auto& [name, c] : counters_) {
    ChannelSummary& s = out[name];
    s.count = c.count;
    s.drops = c.drops;
    s.late = c.late;
    s.malformed = c.malformed;
    s.wall_clock = std::find(cfg_.wall_clock_channels.begin(), cfg_.wall_clock_channels.end(), name) !=
                   cfg_.wall_clock_channels.end();
    const double basis = s.wall_clock ? wall_duration_s : sim_duration_s;
    s.rate_hz = basis > 0 ? static_cast<double>(c.count) / basis : 0.0;
  }
  return out;
}

}  // namespace nimble::launcher
