#pragma once
/// The pilot on the RC transmitter: holds the altitude through the throttle.
///
/// The thesis's flights were flown in an OptiTrack arena by a pilot with an RC transmitter;
/// the manoeuvres were automated onboard (roll set-points and the throttle factor THRF of
/// thesis Eq 7.1), the altitude was the pilot's ("This prevented the Delfly Nimble losing
/// altitude", thesis §7.2.1). The rig models that pilot as a human operator in a compensatory
/// height task: a second-order height loop closed through the throttle, seen through a
/// reaction delay,
///
///   h_seen(t)      = motion-capture height at t - reaction_delay_s
///   hdot_seen(t)   = (h_seen(t) - h(t - reaction_delay_s - speed_window_s)) / speed_window_s
///   a_cmd          = bandwidth^2 (h_ref - h_seen) - 2 damping bandwidth hdot_seen     [m/s^2]
///   correction_pct = clamp(a_cmd / accel_per_pct, +-max_correction_pct)               [%]
///
/// with h_ref the first height the pilot sees (the hover the run starts from) and accel_per_pct
/// the vertical acceleration one % of throttle gives at trim (the pilot knows the vehicle):
/// thrust_curve'(f_trim) * throttle_to_freq / mass, mass = thrust_curve(f_trim) / g. The
/// correction is added to the throttle set-point before THRF multiplies it, as the RC throttle
/// is onboard. Every parameter is an assumption (no published figure): rig_configs/pilot/.
///
/// Deterministic in lockstep: the pilot only uses heights measured reaction_delay_s ago or
/// earlier, which were published long before the cycle that uses them (reaction_delay_s must
/// exceed the motion capture's latency by far; the loader requires at least 0.05 s).

#include <deque>
#include <utility>

#include "core/config.h"
#include "core/param_table.h"

namespace nimble {

struct PilotConfig {
  /// The pilot flies the throttle (true) or leaves it at the manoeuvre's (false).
  bool enabled = false;
  /// Time from what the pilot sees to the throttle he gives [s]: human operator's effective
  /// delay in a compensatory task, 0.2-0.3 s (McRuer's crossover model; assumption).
  double reaction_delay_s = 0.25;
  /// Natural frequency of the height loop [rad/s] (assumption: a pilot holding a hovering
  /// vehicle's height reacts in about a second).
  double bandwidth_radps = 1.0;
  /// Damping ratio of the height loop [-] (assumption: a calm, well-damped correction).
  double damping = 1.0;
  /// Window over which the pilot judges the climb rate from the height [s] (assumption).
  double speed_window_s = 0.1;
  /// Largest throttle correction the pilot gives [%] (assumption).
  double max_correction_pct = 15.0;
};

/// The `pilot` section's parameters (defaults: PilotConfig's; rig_configs/pilot/rc_pilot.yaml
/// has the paper scenarios' values with their sources).
const ParamTable<PilotConfig>& pilot_params();

/// Reads the `pilot` section (absent: disabled). @throws ConfigError naming the key.
PilotConfig pilot_config_from(ConfigMap& map);

class AltitudePilot {
 public:
  /// @param accel_per_pct_mps2 vertical acceleration per % of throttle at trim [m/s^2 per %], > 0.
  /// @throws std::invalid_argument if it is not positive and finite, or the configuration is bad.
  AltitudePilot(const PilotConfig& config, double accel_per_pct_mps2);

  /// A motion-capture height (up positive) [m] measured at `t_s` [s]. Samples must come in
  /// time order; one that is not later than the last is ignored (returns false).
  bool observe(double t_s, double height_m);

  /// Throttle correction [%] at time `t_s`: 0 until the pilot has seen a height and its rate.
  double correction_pct(double t_s);

  /// The height the pilot holds [m]; NaN before the first sample.
  double reference_m() const { return h_ref_; }
  const PilotConfig& config() const { return cfg_; }

 private:
  /// The newest sample at or before `t_s`, or nullptr.
  const std::pair<double, double>* seen_at(double t_s) const;

  PilotConfig cfg_;
  double accel_per_pct_;
  double h_ref_;
  std::deque<std::pair<double, double>> samples_;  ///< (time, height), time ascending
};

/// Vertical acceleration per % of throttle at trim [m/s^2 per %] for a controller whose trim
/// collective is `f_trim_radps` and whose throttle map is `radps_per_pct`, on the thrust curve
/// of core/thrust_curve.h, with weight = thrust at trim.
double throttle_accel_per_pct(double f_trim_radps, double radps_per_pct, double gravity_mps2 = 9.81);

}  // namespace nimble
