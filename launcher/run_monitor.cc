#include "launcher/run_monitor.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <cstdio>

#include <optional>

#include <nimble/fault_event_t.hpp>
#include <nimble/heartbeat_t.hpp>
#include <nimble/rig_message_list.hpp>
#include <nimble/step_ack_t.hpp>
#include <nimble/timing_health_t.hpp>

#include "contract/channels.h"
#include "contract/decode.h"
#include "contract/messages.h"

namespace nimble::launcher {
namespace {

using namespace contract::channels;

/// Publisher names a run's messages may carry besides its processes.
bool known_publisher(const MonitorConfig& cfg, const std::string& name) {
  if (name == "launcher" || name == "logger") return true;
  return cfg.processes.empty() || std::find(cfg.processes.begin(), cfg.processes.end(), name) != cfg.processes.end();
}

/// A stream message of the contract as the monitor uses it: decoded exactly as its channel's
/// type, its header (utime, seq) and, for the channels the summary reads, its value
/// (contract/messages.h).
struct StreamMessage {
  int64_t utime = 0;
  int64_t seq = 0;
  int64_t latency_us = 0;  ///< a pose's exposure-to-publication latency: it is due this much after utime
  std::optional<Truth> truth;
  std::optional<Estimate> estimate;
  std::optional<ControllerStatus> status;
};

template <class Message>
std::optional<Message> decoded(const void* data, int size, bool own_encoding) {
  Message m{};
  if (!contract::decode_as(data, size, m, own_encoding)) return std::nullopt;
  return m;
}

/// The stream message on `channel`, or nothing if the bytes are not exactly its channel's type
/// (contract/channels.h). The channels the summary reads are decoded to their values; any other
/// channel of the contract to its header, whatever its type (the generated list of types).
std::optional<StreamMessage> decode_stream(const std::string& channel, const void* data, int size, bool own_encoding) {
  StreamMessage s;
  const auto header = [&s](const auto& m) {
    s.utime = m.utime;
    s.seq = m.seq;
    return std::optional<StreamMessage>(s);
  };
  if (channel == kTruth) {
    const auto m = decoded<truth_state_t>(data, size, own_encoding);
    if (!m) return std::nullopt;
    s.truth = contract::from_message(*m);
    return header(*m);
  }
  if (channel == kEstimate) {
    const auto m = decoded<estimator_state_t>(data, size, own_encoding);
    if (!m) return std::nullopt;
    s.estimate = contract::from_message(*m);
    return header(*m);
  }
  if (channel == kMocapPose) {
    const auto m = decoded<mocap_pose_t>(data, size, own_encoding);
    if (!m) return std::nullopt;
    s.latency_us = contract::from_message(*m).latency_us;
    return header(*m);
  }
  if (channel == kControllerStatus) {
    const auto m = decoded<controller_status_t>(data, size, own_encoding);
    if (!m) return std::nullopt;
    s.status = contract::from_message(*m);
    return header(*m);
  }
  const contract::ChannelSpec* spec = contract::find_channel(channel);
  if (spec == nullptr) return std::nullopt;  // not a channel of the contract
  std::optional<StreamMessage> out;
  with_message_type(spec->type, [&](auto type) {
    if (const auto m = decoded<typename decltype(type)::type>(data, size, own_encoding)) out = header(*m);
  });
  return out;
}

}  // namespace

void TrackingRecorder::add(double t_s, double e, double reference_deg) {
  if (!std::isfinite(e) || !std::isfinite(reference_deg)) return;
  ++s_.samples;
  sum2_ += e * e;
  if (std::fabs(e) > s_.max_deg) {
    s_.max_deg = std::fabs(e);
    s_.max_at_s = t_s;
  }
  if (s_.samples == 1) {
    crossing_s_ = t_s;
  } else if ((e > 0.0) != (last_e_ > 0.0)) {
    crossing_s_ = last_t_ + (t_s - last_t_) * last_e_ / (last_e_ - e);  // interpolated
  }
  last_t_ = t_s;
  last_e_ = e;
  const int side = e > kDeadBandDeg ? 1 : e < -kDeadBandDeg ? -1 : 0;
  if (side != 0 && side != side_) {
    if (!s_.half_cycles.empty()) s_.half_cycles.back().end_s = crossing_s_;
    s_.half_cycles.push_back(TrackingHalfCycle{crossing_s_, t_s, e, 0.0});
    reference_min_ = reference_max_ = reference_deg;
    side_ = side;
  }
  if (side_ == 0) return;
  TrackingHalfCycle& h = s_.half_cycles.back();
  h.end_s = t_s;
  if (side_ * e > side_ * h.peak_deg) h.peak_deg = e;
  reference_min_ = std::min(reference_min_, reference_deg);
  reference_max_ = std::max(reference_max_, reference_deg);
  h.reference_range_deg = reference_max_ - reference_min_;
}

TrackingSummary TrackingRecorder::summary() const {
  TrackingSummary s = s_;
  if (s.samples > 0) s.rms_deg = std::sqrt(sum2_ / static_cast<double>(s.samples));
  return s;
}

bool RunMonitor::accept_seq(Counter& c, const std::string& publisher, int64_t seq) {
  const auto it = c.last_seq.find(publisher);
  const int64_t last = it == c.last_seq.end() ? -1 : it->second;
  if (!contract::seq_continues(last, seq)) return false;
  if (last >= 0 && seq > last + 1) c.drops += seq - last - 1;
  c.last_seq[publisher] = seq;
  return true;
}

void RunMonitor::add_truth(const Truth& t, int64_t utime) {
  const double p = t.omega_body_radps[0], v = t.velocity_body_mps[1], phi = t.euler_rad[0];
  FlightSummary& f = flight_;
  if (!std::isfinite(p) || !std::isfinite(v) || !std::isfinite(phi) || !std::isfinite(t.euler_rad[1])) f.finite = false;
  if (f.samples == 0) {
    f.min_p = f.max_p = p;
    f.min_v = f.max_v = v;
    f.min_phi = f.max_phi = phi;
    f.min_df = f.max_df = t.delta_f_radps;
    start_down_m_ = t.position_ned_m[2];
    f.min_w = f.max_w = f.initial_w = t.velocity_body_mps[2];
  }
  const double height = start_down_m_ - t.position_ned_m[2], w = t.velocity_body_mps[2];
  if (!std::isfinite(height) || !std::isfinite(w)) f.finite = false;
  f.min_height_m = std::min(f.min_height_m, height);
  f.max_height_m = std::max(f.max_height_m, height);
  f.final_height_m = height;
  f.min_w = std::min(f.min_w, w);
  f.max_w = std::max(f.max_w, w);
  ++f.samples;
  f.max_abs_p = std::max(f.max_abs_p, std::fabs(p));
  f.max_abs_v = std::max(f.max_abs_v, std::fabs(v));
  f.max_abs_phi = std::max(f.max_abs_phi, std::fabs(phi));
  f.max_abs_theta = std::max(f.max_abs_theta, std::fabs(t.euler_rad[1]));
  f.max_abs_psi = std::max(f.max_abs_psi, std::fabs(t.euler_rad[2]));
  f.min_p = std::min(f.min_p, p);
  f.max_p = std::max(f.max_p, p);
  f.min_v = std::min(f.min_v, v);
  f.max_v = std::max(f.max_v, v);
  f.min_phi = std::min(f.min_phi, phi);
  f.max_phi = std::max(f.max_phi, phi);
  f.min_df = std::min(f.min_df, t.delta_f_radps);
  f.max_df = std::max(f.max_df, t.delta_f_radps);
  f.final_p = p;
  f.final_v = v;
  f.final_phi = phi;
  f.last_sim_time_s = t.time_s;
  if (cfg_.trace_interval_us > 0) {
    f.trace_dt_s = static_cast<double>(cfg_.trace_interval_us) / 1e6;
    // Every grid time this TRUTH is the first at or after (a gap in TRUTH repeats it).
    while (static_cast<int64_t>(f.trace_p.size()) * cfg_.trace_interval_us <= utime) {
      f.trace_p.push_back(p);
      f.trace_v.push_back(v);
      f.trace_phi.push_back(phi);
    }
  }
  recent_truth_[utime] = TruthPoint{phi, p, v};
  while (!recent_truth_.empty() && recent_truth_.begin()->first < utime - 1000000) {
    recent_truth_.erase(recent_truth_.begin());
  }
}

void RunMonitor::add_estimate(const Estimate& e) {
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

void RunMonitor::add_status(const ControllerStatus& status, int64_t utime) {
  // The true roll the cycle saw: the newest TRUTH at or before its time.
  auto it = recent_truth_.upper_bound(utime);
  if (it == recent_truth_.begin()) return;
  --it;
  const double error = std::remainder(status.roll_ref_rad - it->second.phi, 2.0 * M_PI);
  tracking_.add(static_cast<double>(utime) / 1e6, error * 180.0 / M_PI, status.roll_ref_rad * 180.0 / M_PI);
}

void RunMonitor::on_message(const std::string& channel, const void* data, int size, int64_t recv_ns,
                            bool own_encoding) {
  // Channels nobody in a run publishes are counted under one name, so that a flood of made-up
  // names cannot grow the table without bound.
  Counter& c =
      counters_[contract::find_channel(channel) != nullptr || channel == "LCM_SELF_TEST" ? channel : "(other)"];
  // A message is counted and used only once it decodes exactly as its channel's type and
  // continues its publisher's seq; anything else is malformed and left out of every figure.
  const auto take = [&](auto& msg, const std::string& publisher) {
    if (!contract::decode_as(data, size, msg, own_encoding) || !known_publisher(cfg_, publisher_of(msg, publisher)) ||
        !accept_seq(c, publisher_of(msg, publisher), msg.seq)) {
      ++c.malformed;
      return false;
    }
    ++c.count;
    return true;
  };

  if (channel == kHeartbeat) {
    heartbeat_t hb{};
    if (take(hb, "")) {
      Heartbeat& h = heartbeat_[hb.process];
      h = Heartbeat{hb.state, hb.pid, hb.config_digest, recv_ns, h.count + 1};
    }
    return;
  }
  if (channel == kTimingHealth) {
    timing_health_t h{};
    if (!take(h, "")) return;
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
    t.stages.clear();
    for (std::size_t i = 0; i < static_cast<std::size_t>(h.num_stages); ++i) {
      t.stages.push_back(
          TimingSummary::Stage{h.stage[i], h.stage_count[i], h.stage_p50_us[i], h.stage_p99_us[i], h.stage_max_us[i]});
    }
    return;
  }
  if (channel == kCanHealth) {
    can_health_t h{};
    if (take(h, "")) can_health_[h.process] = contract::from_message(h);
    return;
  }
  if (channel == kFault) {
    fault_event_t message{};
    if (take(message, "")) {
      const FaultEvent f = contract::from_message(message);
      faults_.push_back(
          FaultRecord{f.process, f.severity, f.code, f.channel, f.message, static_cast<double>(f.rig_utime) / 1e6});
    }
    return;
  }
  if (channel == kStepAck) {
    step_ack_t a{};
    take(a, "");
    return;
  }
  if (contract::find_channel(channel) == nullptr) {  // not the rig's: counted, not judged
    ++c.count;
    return;
  }

  // Stream channels: one publisher; a message that does not decode exactly as its channel's
  // type, or does not continue its seq, is not counted at all.
  const std::optional<StreamMessage> m = decode_stream(channel, data, size, own_encoding);
  if (!m || !accept_seq(c, "", m->seq)) {
    ++c.malformed;
    return;
  }
  ++c.count;
  // A message is due at its utime; a pose is stamped at mid-exposure and due latency_us later.
  const int64_t utime = m->utime;
  const int64_t due_us = utime + m->latency_us;
  if (!cfg_.lockstep && cfg_.t0_monotonic_ns > 0 && contract::due_in_sim_time(channel)) {
    const int64_t lag_us = (recv_ns - cfg_.t0_monotonic_ns) / 1000 - due_us;
    if (lag_us > cfg_.late_threshold_us) ++c.late;
  }
  if (m->truth) add_truth(*m->truth, utime);
  if (m->estimate) add_estimate(*m->estimate);
  if (m->status) add_status(*m->status, utime);
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
  return it == heartbeat_.end() ? -1 : it->second.state;
}

const RunMonitor::Heartbeat* RunMonitor::heartbeat(const std::string& process) const {
  const auto it = heartbeat_.find(process);
  return it == heartbeat_.end() ? nullptr : &it->second;
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
