#include "launcher/verdict.h"

#include <cmath>
#include <cstdio>

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

}  // namespace

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
                   (from.empty() ? "" : " (published by " + from + ")") + " (limit " +
                   percent(jc.max_late_fraction) + ")");
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
                  const TimingVerdict& timing, bool strict_timing, const std::string& failsafe) {
  constexpr double kRad = M_PI / 180.0;
  Verdict v;
  v.controlled = f.samples > 0 && f.finite && f.max_abs_phi <= jc.max_phi_deg * kRad &&
                 f.max_abs_theta <= jc.max_theta_deg * kRad;
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
  } else if (timing.degraded) {
    v.exit_code = strict_timing ? kRunTimingDegraded : kRunOk;
    v.text = timing.text;
  } else {
    v.exit_code = kRunOk;
    v.text = "ok";
  }
  v.timing = timing;
  return v;
}

}  // namespace nimble::launcher
