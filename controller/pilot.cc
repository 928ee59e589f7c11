#include "controller/pilot.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/thrust_curve.h"

namespace nimble {

const ParamTable<PilotConfig>& pilot_params() {
  using C = PilotConfig;
  static const ParamTable<C> table = {
      {"enabled", &C::enabled, Range{}, "-", "the pilot holds the altitude through the throttle"},
      // At least 50 ms: the pilot then only uses poses published long before the cycle (lockstep determinism).
      {"reaction_delay_s", &C::reaction_delay_s, Range::closed(0.05, 1.0), "s",
       "from what the pilot sees to the throttle he gives (assumption: 0.2-0.3 s, human operator)"},
      {"bandwidth_radps", &C::bandwidth_radps, Range{0.0, 5.0, true, false}, "rad/s",
       "natural frequency of the pilot's height loop (assumption)"},
      {"damping", &C::damping, Range::closed(0.3, 3.0), "-", "damping ratio of the pilot's height loop (assumption)"},
      {"speed_window_s", &C::speed_window_s, Range::closed(0.01, 0.5), "s",
       "window over which the pilot judges the climb rate (assumption)"},
      {"max_correction_pct", &C::max_correction_pct, Range{0.0, 50.0, true, false}, "%",
       "largest throttle correction the pilot gives (assumption)"},
  };
  return table;
}

PilotConfig pilot_config_from(ConfigMap& map) {
  PilotConfig c;
  read_params(map, pilot_params(), c);
  map.finish();
  return c;
}

double throttle_accel_per_pct(double f_trim_radps, double radps_per_pct, double gravity_mps2) {
  const ThrustCurve curve;
  const double weight_n = curve.thrust_n(f_trim_radps);
  const double slope_n_per_radps = curve.thrust_n(f_trim_radps + 1.0) - weight_n;  // the curve is affine
  return gravity_mps2 * slope_n_per_radps * radps_per_pct / weight_n;
}

AltitudePilot::AltitudePilot(const PilotConfig& config, double accel_per_pct_mps2)
    : cfg_(config), accel_per_pct_(accel_per_pct_mps2), h_ref_(std::numeric_limits<double>::quiet_NaN()) {
  if (!(std::isfinite(accel_per_pct_mps2) && accel_per_pct_mps2 > 0.0)) {
    throw std::invalid_argument("pilot: the throttle's vertical acceleration must be > 0 m/s^2 per %, got " +
                                std::to_string(accel_per_pct_mps2));
  }
  check_params(pilot_params(), cfg_);
}

bool AltitudePilot::observe(double t_s, double height_m) {
  if (!std::isfinite(t_s) || !std::isfinite(height_m)) return false;
  if (!samples_.empty() && t_s <= samples_.back().first) return false;
  if (samples_.empty()) h_ref_ = height_m;
  samples_.emplace_back(t_s, height_m);
  // Keep what the oldest look-up (delay + window) still needs, plus one sample before it.
  const double keep_after = t_s - 2.0 * (cfg_.reaction_delay_s + cfg_.speed_window_s) - 0.1;
  while (samples_.size() > 2 && samples_[1].first < keep_after) samples_.pop_front();
  return true;
}

const std::pair<double, double>* AltitudePilot::seen_at(double t_s) const {
  // Samples are in time order: the last one at or before t_s.
  const auto it = std::upper_bound(samples_.begin(), samples_.end(), t_s,
                                   [](double t, const std::pair<double, double>& s) { return t < s.first; });
  return it == samples_.begin() ? nullptr : &*(it - 1);
}

double AltitudePilot::correction_pct(double t_s) {
  const double seen_t = t_s - cfg_.reaction_delay_s;
  const auto* now = seen_at(seen_t);
  const auto* before = seen_at(seen_t - cfg_.speed_window_s);
  if (now == nullptr || before == nullptr || now->first <= before->first) return 0.0;
  const double h = now->second;
  const double hdot = (now->second - before->second) / (now->first - before->first);
  const double w = cfg_.bandwidth_radps;
  const double accel = w * w * (h_ref_ - h) - 2.0 * cfg_.damping * w * hdot;
  // Heights so far apart that the arithmetic overflows are no height a pilot acts on.
  if (!std::isfinite(accel)) return 0.0;
  return std::clamp(accel / accel_per_pct_, -cfg_.max_correction_pct, cfg_.max_correction_pct);
}

}  // namespace nimble
