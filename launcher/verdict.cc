#include "launcher/verdict.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <fmt/format.h>
#include <nimble/fault_event_t.hpp>

#include "contract/channels.h"

namespace nimble::launcher {

namespace {

std::string percent(double fraction) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f %%", 100.0 * fraction);
  return buf;
}

std::string publishers_of(const std::string& channel) {
  const contract::ChannelSpec* spec = contract::find_channel(channel);
  if (spec == nullptr || spec->publishers.empty()) return "";
  std::string out;
  for (const auto& p : spec->publishers) out += (out.empty() ? "" : ", ") + p;
  return out;
}

/// Damping ratio of an oscillation whose amplitude changes by `ratio` each cycle (from the
/// logarithmic decrement); negative for a growing one.
double damping_of(double ratio) {
  const double decrement = -std::log(ratio);
  return decrement / std::sqrt(4.0 * M_PI * M_PI + decrement * decrement);
}

/// Damping ratio of half-cycles [first, first + count): from the least-squares slope of the log
/// of the mean |peak| of each two half-cycles in a row (the pair cancels an offset of the
/// error, which makes one side's peaks larger than the other's).
double damping_over(const std::vector<TrackingHalfCycle>& h, std::size_t first, std::size_t count) {
  const double n = static_cast<double>(count - 1);
  double sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0;
  for (std::size_t k = 0; k + 1 < count; ++k) {
    const double x = static_cast<double>(k);
    const double y = std::log((std::fabs(h[first + k].peak_deg) + std::fabs(h[first + k + 1].peak_deg)) / 2.0);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);  // per half-cycle
  return damping_of(std::exp(2.0 * slope));
}

/// One full period: half-cycle i and the one before it [s].
double period_s(const std::vector<TrackingHalfCycle>& h, std::size_t i) { return h[i].end_s - h[i - 1].start_s; }

/// Whether half-cycles [first, first + count) can be one oscillation: every |peak| reaches the
/// amplitude, the reference is still in each, every full period is within the tolerance of
/// their mean.
bool alike(const std::vector<TrackingHalfCycle>& h, std::size_t first, std::size_t count, const JudgeConfig& jc) {
  double sum = 0.0;
  for (std::size_t i = first; i < first + count; ++i) {
    if (std::fabs(h[i].peak_deg) < jc.oscillation_amplitude_deg ||
        h[i].reference_range_deg >= jc.oscillation_reference_still_deg) {
      return false;
    }
    if (i > first) sum += period_s(h, i);
  }
  const double mean = sum / static_cast<double>(count - 1);
  for (std::size_t i = first + 1; i < first + count; ++i) {
    if (std::fabs(period_s(h, i) - mean) > jc.oscillation_period_tolerance * mean) return false;
  }
  return true;
}

}  // namespace

Oscillation find_oscillation(const std::vector<TrackingHalfCycle>& h, const JudgeConfig& jc) {
  Oscillation o;
  const std::size_t window = 2 * static_cast<std::size_t>(std::max(jc.oscillation_cycles, 2));
  const std::size_t closed = h.empty() ? 0 : h.size() - 1;  // the last is still in progress
  const auto amplitude = [&h](std::size_t i) { return std::fabs(h[i].peak_deg); };
  for (std::size_t j = 0; j + window <= closed; ++j) {
    if (!alike(h, j, window, jc)) continue;
    const double zeta = damping_over(h, j, window);
    if (!(zeta < jc.oscillation_max_damping)) continue;
    o.detected = true;
    o.growing = true;
    for (std::size_t i = j + 2; i < j + window; ++i) o.growing = o.growing && amplitude(i) > amplitude(i - 2);
    o.damping_ratio = zeta;
    o.start_s = h[j].start_s;
    std::size_t end = j + window;
    while (end < closed && alike(h, end + 1 - window, window, jc)) ++end;
    o.cycles = static_cast<int>((end - j) / 2);
    o.frequency_hz = static_cast<double>(end - j) / 2.0 / (h[end - 1].end_s - h[j].start_s);
    for (std::size_t i = j; i < end; ++i) o.amplitude_deg = std::max(o.amplitude_deg, amplitude(i));
    o.text = fmt::format("roll oscillation {:.1f} Hz +-{:.0f} deg {} from t = {:.1f} s", o.frequency_hz,
                         o.amplitude_deg, o.growing ? "growing" : "sustained", o.start_s);
    return o;
  }
  return o;
}

TrackingVerdict judge_tracking(const TrackingSummary& t, const JudgeConfig& jc) {
  TrackingVerdict v;
  if (t.samples == 0) return v;
  v.judged = true;
  v.rms_deg = t.rms_deg;
  v.max_deg = t.max_deg;
  v.max_at_s = t.max_at_s;
  v.oscillation = find_oscillation(t.half_cycles, jc);
  std::vector<std::string> lost;
  if (v.oscillation.detected) lost.push_back(v.oscillation.text);
  if (t.rms_deg > jc.max_tracking_rms_deg) {
    lost.push_back(
        fmt::format("roll tracking error rms {:.1f} deg (limit {:g} deg)", t.rms_deg, jc.max_tracking_rms_deg));
  }
  if (t.max_deg > jc.max_tracking_error_deg) {
    lost.push_back(fmt::format("roll tracking error {:.1f} deg at t = {:.2f} s (limit {:g} deg)", t.max_deg, t.max_at_s,
                               jc.max_tracking_error_deg));
  }
  v.lost = !lost.empty();
  for (const auto& l : lost) v.text += (v.text.empty() ? "" : "; ") + l;
  return v;
}

TimingVerdict judge_timing(const std::map<std::string, TimingSummary>& timing, const JudgeConfig& jc, bool realtime) {
  TimingVerdict v;
  if (!realtime) return v;
  v.judged = true;
  // The worst finding relative to its threshold (a threshold of 0 makes any count degrading).
  double worst_ratio = -1.0;
  std::string worst_text;
  const auto consider = [&](double fraction, double threshold, const std::string& process, const std::string& text) {
    const double ratio = threshold > 0.0 ? fraction / threshold : (fraction > 0.0 ? 1e300 : 0.0);
    if (ratio > worst_ratio) {
      worst_ratio = ratio;
      v.worst = process;
      v.worst_fraction = fraction;
      worst_text = text;
    }
    if (fraction > threshold) v.degraded = true;
  };
  for (const auto& [process, t] : timing) {
    if (t.loop_count > 0) {
      const double f = static_cast<double>(t.overruns) / static_cast<double>(t.loop_count);
      consider(f, jc.max_overrun_fraction, process,
               process + " overran " + percent(f) + " of its " + std::to_string(t.loop_count) + " cycles (limit " +
                   percent(jc.max_overrun_fraction) + ")");
    }
    for (const auto& [channel, r] : t.received) {
      if (r.count <= 0) continue;
      const double f = static_cast<double>(r.late) / static_cast<double>(r.count);
      const std::string from = publishers_of(channel);
      consider(f, jc.max_late_fraction, process,
               percent(f) + " of " + channel + " arrived late at " + process +
                   (from.empty() ? "" : " (published by " + from + ")") + " (limit " + percent(jc.max_late_fraction) +
                   ")");
    }
  }
  if (worst_ratio < 0.0) {
    v.text = "real-time health not reported (no TIMING_HEALTH)";
  } else {
    v.text = std::string(v.degraded ? "real-time degraded: " : "real-time ok; worst: ") + worst_text;
  }
  return v;
}

std::string failsafe_of(const RunMonitor& monitor) {
  for (const auto& f : monitor.faults()) {
    if (f.code == fault_event_t::CODE_FAILSAFE && f.severity >= fault_event_t::SEVERITY_ERROR) {
      return f.process + ": " + f.message;
    }
  }
  return "";
}

Verdict judge_run(const FlightSummary& f, const JudgeConfig& jc, bool interrupted, const std::string& failure,
                  const TimingVerdict& timing, bool strict_timing, const std::string& failsafe,
                  const TrackingVerdict& tracking) {
  constexpr double kRad = M_PI / 180.0;
  Verdict v;
  v.controlled =
      f.samples > 0 && f.finite && f.max_abs_phi <= jc.max_phi_deg * kRad && f.max_abs_theta <= jc.max_theta_deg * kRad;
  v.hover = v.controlled && std::fabs(f.final_phi) <= jc.hover_phi_deg * kRad &&
            std::fabs(f.final_p) <= jc.hover_p_radps && std::fabs(f.final_v) <= jc.hover_v_mps;
  if (interrupted) {
    v.exit_code = kRunInterrupted;
    v.text = "interrupted";
  } else if (!failure.empty()) {
    v.exit_code = kRunFailed;
    v.text = "failed: " + failure.substr(0, failure.find('\n'));
  } else if (!failsafe.empty()) {
    // The manoeuvre was not flown to its end: whatever the vehicle did, the failsafe decided it.
    v.exit_code = kRunFailsafe;
    v.text = std::string("completed in failsafe (vehicle ") + (v.controlled ? "within" : "beyond") +
             " the control limits): " + failsafe;
  } else if (!v.controlled) {
    v.exit_code = kRunNotControlled;
    v.text = "completed, vehicle NOT controlled";
    if (tracking.oscillation.detected) v.text += " (" + tracking.oscillation.text + ")";
  } else if (tracking.lost) {
    v.exit_code = kRunNotTracking;
    v.text = "completed, " + tracking.text;
  } else if (timing.degraded) {
    v.exit_code = strict_timing ? kRunTimingDegraded : kRunOk;
    v.text = timing.text;
  } else {
    v.exit_code = kRunOk;
    v.text = "ok";
  }
  v.timing = timing;
  v.tracking = tracking;
  return v;
}

}  // namespace nimble::launcher
