#include "controller/attitude_controller.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "core/constants.h"
#include "contract/rates.h"
#include "core/config.h"

namespace nimble {
namespace {

/// T = 2 (0.0114 f_hz - 0.0449) N (thesis Eq 4.18).

/// A bad parameter: its key path as in the YAML file, its value and what is wrong.
class InvalidParameter : public std::invalid_argument {
 public:
  InvalidParameter(std::string key, std::string value, std::string problem)
      : std::invalid_argument("controller config: " + key + (value.empty() ? "" : " = " + value) + ": " + problem),
        key_(std::move(key)),
        value_(std::move(value)),
        problem_(std::move(problem)) {}
  const std::string& key() const { return key_; }
  const std::string& value() const { return value_; }
  const std::string& problem() const { return problem_; }

 private:
  std::string key_, value_, problem_;
};

[[noreturn]] void bad(const std::string& name, double value, const std::string& allowed) {
  throw InvalidParameter(name, general_text(value), "must be " + allowed);
}

void check(bool ok, const std::string& name, double value, const std::string& allowed) {
  if (!ok || !std::isfinite(value)) bad(name, value, allowed);
}

bool valid_name(const std::string& name) {
  if (name.empty()) return false;
  for (const char c : name) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-')) return false;
  }
  return true;
}

std::string known_sets(const ControllerConfig& config) {
  std::string list;
  for (const auto& item : config.roll_gain_sets) list += (list.empty() ? "" : ", ") + item.first;
  return list;
}

// Allowed ranges, shared by validate() and the loader.
const Range kRateHz = Range::closed(contract::kMinControlRateHz, contract::kMaxControlRateHz);
const Range kZeta = Range::closed(0.0, 5.0);
const Range kSetpointMaxRad{0.0, 0.5 * kPi, true, true};
const Range kGain = Range::closed(0.0, 100.0);
const Range kRollMap{0.0, 1000.0, true, false};
const Range kMixAbs = Range::closed(0.0, 1.0);
const Range kPitchMap = Range::closed(0.0, 1.0);
const Range kTrimThrottle{0.0, 100.0, true, true};
const Range kFreq = Range::closed(0.0, 1000.0);
const Range kThrottleMap = Range::closed(0.0, 50.0);

/// A table's first violation as the controller's InvalidParameter, its key under `prefix`.
template <typename C>
void check_table(const ParamTable<C>& table, const C& config, const std::string& prefix) {
  if (const auto v = first_violation(table, config))
    throw InvalidParameter(prefix + v->key, v->value, "must be " + v->allowed);
}

void check_reference(const std::string& axis, const ReferenceGeneratorConfig& r) {
  check_table(reference_params(), r, axis + ".");
}

void check_gains(const std::string& name, const GainSet& g) { check_table(gain_params(), g, name + "."); }

ReferenceGeneratorConfig reference_from(ConfigMap& map, const ReferenceGeneratorConfig& base) {
  ReferenceGeneratorConfig r = base;
  read_params(map, reference_params(), r);
  map.finish();
  return r;
}

GainSet gains_from(ConfigMap& map, const GainSet& base) {
  GainSet g = base;
  read_params(map, gain_params(), g);
  map.finish();
  return g;
}

}  // namespace

const ParamTable<ControllerConfig>& controller_params() {
  using C = ControllerConfig;
  static const ParamTable<C> table = {
      {"rate_hz", &C::rate_hz, kRateHz, "Hz", "control rate; thesis: 512 Hz onboard loop"},
      {"mixing.roll_cmd_to_delta_f_radps", &C::roll_cmd_to_delta_f_radps, kRollMap, "rad/s",
       "flapping-frequency difference per unit roll command (calibrated, see the controller file)"},
      {"mixing.mix_abs_roll_gain", &C::mix_abs_roll_gain, kMixAbs, "-",
       "collective added per |roll command|, onboard mixing 0.1 |roll|"},
      {"mixing.pitch_cmd_to_dihedral_rad", &C::pitch_cmd_to_dihedral_rad, kPitchMap, "rad",
       "dihedral per unit pitch command"},
      {"yaw.enabled", &C::yaw_enabled, Range{}, "-", "the yaw loop flies the wing-root servo (four-state models)"},
      {"yaw.cmd_to_wing_root_rad", &C::yaw_cmd_to_wing_root_rad, Range::closed(-1.0, 1.0), "rad",
       "wing-root angle per unit yaw command; negative: N_dw < 0 (Table 8.3)"},
      {"throttle.trim_throttle_pct", &C::trim_throttle_pct, kTrimThrottle, "%", "throttle at trim"},
      {"throttle.f_trim_radps", &C::f_trim_radps, Range{0.0, 1000.0, true, false}, "rad/s",
       "collective flapping frequency at trim, within the limits"},
      {"throttle.throttle_to_freq_radps_per_pct", &C::throttle_to_freq_radps_per_pct, kThrottleMap, "rad/s/%",
       "collective per % throttle; the plant's collective_radps_per_pct"},
      {"limits.flap_freq_min_radps", &C::flap_freq_min_radps, kFreq, "rad/s", "lowest flapping-frequency command"},
      {"limits.flap_freq_max_radps", &C::flap_freq_max_radps, Range{0.0, 1000.0, true, false}, "rad/s",
       "highest flapping-frequency command, above the lowest"},
      {"failsafe.input_stale_s", &C::input_stale_s, Range{0.0, 10.0, true, false}, "s",
       "an input older than this engages the failsafe"},
      {"failsafe.first_input_timeout_s", &C::first_input_timeout_s, Range{0.0, 60.0, true, false}, "s",
       "no input at all by this time engages the failsafe"},
      {"failsafe.throttle_pct", &C::failsafe_throttle_pct, Range::closed(0.0, 100.0), "%",
       "throttle of the failsafe (neutral roll and pitch)"},
  };
  return table;
}

const ParamTable<ReferenceGeneratorConfig>& reference_params() {
  using C = ReferenceGeneratorConfig;
  static const ParamTable<C> table = {
      {"omega_radps", &C::omega_radps, Range::positive(), "rad/s", "natural frequency; 800 deg/s in the onboard code"},
      {"zeta", &C::zeta, kZeta, "-", "damping ratio"},
      {"rate_max_radps", &C::rate_max_radps, Range::positive(), "rad/s", "limit on |rate_ref|; 400 deg/s"},
      {"accel_max_radps2", &C::accel_max_radps2, Range::positive(), "rad/s^2", "limit on |accel_ref|; 8000 deg/s^2"},
      {"setpoint_max_rad", &C::setpoint_max_rad, kSetpointMaxRad, "rad", "limit on |angle set-point|; 60 deg"},
  };
  return table;
}

const ParamTable<GainSet>& gain_params() {
  using C = GainSet;
  static const ParamTable<C> table = {
      {"kp_per_rad", &C::kp_per_rad, kGain, "1/rad", "proportional gain: normalised command per rad of angle error"},
      {"kd_per_radps", &C::kd_per_radps, kGain, "s/rad", "derivative gain: normalised command per rad/s of rate error"},
  };
  return table;
}

double flap_thrust_n(double f_radps) { return ThrustCurve{}.thrust_n(f_radps); }

double hover_flap_frequency_radps(double mass_kg, double gravity_mps2) {
  if (!(std::isfinite(mass_kg) && mass_kg > 0.0)) {
    throw std::invalid_argument("hover_flap_frequency_radps: mass_kg must be > 0, got " + general_text(mass_kg));
  }
  if (!(std::isfinite(gravity_mps2) && gravity_mps2 > 0.0)) {
    throw std::invalid_argument("hover_flap_frequency_radps: gravity_mps2 must be > 0, got " +
                                general_text(gravity_mps2));
  }
  return ThrustCurve{}.frequency_radps(mass_kg * gravity_mps2);
}

void validate(const ControllerConfig& c) {
  check_table(controller_params(), c, "");
  check_reference("reference.roll", c.roll_reference);
  check_reference("reference.pitch", c.pitch_reference);
  const Range cutoff{0.0, 0.5 * c.rate_hz, true, true};
  check(cutoff.contains(c.roll_lowpass_cutoff_hz), "lowpass.roll_cutoff_hz", c.roll_lowpass_cutoff_hz,
        cutoff.describe() + " (below Nyquist)");
  check(cutoff.contains(c.pitch_lowpass_cutoff_hz), "lowpass.pitch_cutoff_hz", c.pitch_lowpass_cutoff_hz,
        cutoff.describe() + " (below Nyquist)");
  if (c.roll_gain_sets.empty()) throw InvalidParameter("roll_gain_sets", "", "must hold at least one gain set");
  for (const auto& item : c.roll_gain_sets) {
    if (!valid_name(item.first)) {
      throw InvalidParameter("roll_gain_sets." + item.first, "", "gain set name must be letters, digits, '_' or '-'");
    }
    check_gains("roll_gain_sets." + item.first, item.second);
  }
  if (c.roll_gain_sets.count(c.default_gain_set) == 0) {
    throw InvalidParameter("default_gain_set", c.default_gain_set,
                           "unknown gain set '" + c.default_gain_set + "' (known: " + known_sets(c) + ")");
  }
  check_gains("pitch_gains", c.pitch_gains);
  check_gains("yaw", c.yaw_gains);
  check(c.flap_freq_max_radps > c.flap_freq_min_radps, "limits.flap_freq_max_radps", c.flap_freq_max_radps,
        "in (flap_freq_min_radps = " + general_text(c.flap_freq_min_radps) + ", 1000]");
  check(c.f_trim_radps >= c.flap_freq_min_radps && c.f_trim_radps <= c.flap_freq_max_radps, "throttle.f_trim_radps",
        c.f_trim_radps, "within [flap_freq_min_radps, flap_freq_max_radps]");
}

const GainSet& roll_gain_set(const ControllerConfig& config, const std::string& name) {
  const auto it = config.roll_gain_sets.find(name);
  if (it == config.roll_gain_sets.end()) {
    throw std::invalid_argument("unknown roll gain set '" + name + "' (known: " + known_sets(config) + ")");
  }
  return it->second;
}

ControllerConfig controller_config_from(ConfigMap& map, const ControllerConfig& base) {
  ControllerConfig c = base;
  read_params(map, controller_params(), c);

  if (map.has("reference")) {
    ConfigMap ref = map.get_map("reference");
    if (ref.has("roll")) {
      ConfigMap roll = ref.get_map("roll");
      c.roll_reference = reference_from(roll, base.roll_reference);
    }
    if (ref.has("pitch")) {
      ConfigMap pitch = ref.get_map("pitch");
      c.pitch_reference = reference_from(pitch, base.pitch_reference);
    }
    ref.finish();
  }

  if (map.has("lowpass")) {
    ConfigMap lp = map.get_map("lowpass");
    const Range cutoff{0.0, 0.5 * c.rate_hz, true, true};
    c.roll_lowpass_cutoff_hz = lp.get_double_or("roll_cutoff_hz", base.roll_lowpass_cutoff_hz, cutoff);
    c.pitch_lowpass_cutoff_hz = lp.get_double_or("pitch_cutoff_hz", base.pitch_lowpass_cutoff_hz, cutoff);
    lp.finish();
  }

  if (map.has("roll_gain_sets")) {
    ConfigMap sets = map.get_map("roll_gain_sets");
    for (const std::string& name : sets.keys()) {
      if (!valid_name(name)) sets.fail(name, "gain set name must be letters, digits, '_' or '-'");
      ConfigMap one = sets.get_map(name);
      const auto it = base.roll_gain_sets.find(name);
      // A new set must give both gains; a known one may override either.
      if (it == base.roll_gain_sets.end()) {
        GainSet g;
        g.kp_per_rad = one.get_double("kp_per_rad", kGain);
        g.kd_per_radps = one.get_double("kd_per_radps", kGain);
        one.finish();
        c.roll_gain_sets[name] = g;
      } else {
        c.roll_gain_sets[name] = gains_from(one, it->second);
      }
    }
    sets.finish();
  }
  if (map.has("default_gain_set")) {
    const std::string name = map.get_string("default_gain_set");
    if (c.roll_gain_sets.count(name) == 0) {
      map.fail("default_gain_set", "unknown gain set '" + name + "' (known: " + known_sets(c) + ")");
    }
    c.default_gain_set = name;
  }

  if (map.has("pitch_gains")) {
    ConfigMap pg = map.get_map("pitch_gains");
    c.pitch_gains = gains_from(pg, base.pitch_gains);
  }

  if (map.has("yaw")) {
    ConfigMap yaw = map.get_map("yaw");
    read_params(yaw, controller_params(), c, "yaw");
    read_params(yaw, gain_params(), c.yaw_gains);  // yaw.kp_per_rad, yaw.kd_per_radps
    yaw.finish();
  }

  if (map.has("mixing")) {
    ConfigMap mix = map.get_map("mixing");
    read_params(mix, controller_params(), c, "mixing");
    mix.finish();
  }

  if (map.has("throttle")) {
    ConfigMap thr = map.get_map("throttle");
    read_params(thr, controller_params(), c, "throttle");
    thr.finish();
  }

  if (map.has("limits")) {
    ConfigMap lim = map.get_map("limits");
    read_params(lim, controller_params(), c, "limits");
    lim.finish();
  }

  if (map.has("failsafe")) {
    ConfigMap fs = map.get_map("failsafe");
    read_params(fs, controller_params(), c, "failsafe");
    fs.finish();
  }
  map.finish();

  try {
    validate(c);
  } catch (const InvalidParameter& e) {
    // Cross-key checks (e.g. trim frequency inside the limits) name the key they fail on.
    throw ConfigError(map.file(), map.key_path(e.key()), e.value(), e.problem());
  }
  return c;
}

ControllerConfig load_controller_config(const std::string& file) {
  ConfigMap map = ConfigMap::load_file(file);
  return controller_config_from(map);
}

AttitudeController::AttitudeController(const ControllerConfig& config)
    : config_((validate(config), config)),
      roll_ref_(config.roll_reference, config.dt_s()),
      pitch_ref_(config.pitch_reference, config.dt_s()),
      roll_lp_(config.roll_lowpass_cutoff_hz, config.rate_hz),
      pitch_lp_(config.pitch_lowpass_cutoff_hz, config.rate_hz),
      yaw_lp_(config.roll_lowpass_cutoff_hz, config.rate_hz) {
  reset();
}

void AttitudeController::reset(double phi_rad, double theta_rad) {
  roll_ref_.reset(phi_rad);
  pitch_ref_.reset(theta_rad);
  roll_lp_.reset(0.0);
  pitch_lp_.reset(0.0);
  yaw_lp_.reset(0.0);
  gain_set_name_ = config_.default_gain_set;
  gains_ = config_.roll_gain_sets.at(gain_set_name_);
  last_phi_ = std::isfinite(phi_rad) ? phi_rad : 0.0;
  last_theta_ = std::isfinite(theta_rad) ? theta_rad : 0.0;
  last_p_ = last_q_ = 0.0;
  last_roll_sp_ = last_phi_;
  last_pitch_sp_ = last_theta_;
  last_factor_ = 1.0;
}

bool AttitudeController::select_gain_set(const std::string& name) {
  const auto it = config_.roll_gain_sets.find(name);
  if (it == config_.roll_gain_sets.end()) {
    ++counters_.unknown_gain_set_requests;
    return false;
  }
  gain_set_name_ = it->first;
  gains_ = it->second;
  return true;
}

double AttitudeController::sanitize(double value, double& last, bool& invalid) {
  if (std::isfinite(value)) {
    last = value;
    return value;
  }
  invalid = true;
  return last;
}

ControllerOutput AttitudeController::step(const ControllerInput& in) {
  ControllerOutput out;
  bool invalid = false;
  const double phi = sanitize(in.phi_rad, last_phi_, invalid);
  const double theta = sanitize(in.theta_rad, last_theta_, invalid);
  const double p = sanitize(in.p_radps, last_p_, invalid);
  const double q = sanitize(in.q_radps, last_q_, invalid);
  const double roll_sp = sanitize(in.roll_sp_rad, last_roll_sp_, invalid);
  const double pitch_sp = sanitize(in.pitch_sp_rad, last_pitch_sp_, invalid);
  const double factor_in = sanitize(in.throttle_factor, last_factor_, invalid);
  const double psi = sanitize(in.psi_rad, last_psi_, invalid);
  const double r = sanitize(in.r_radps, last_r_, invalid);
  ++counters_.steps;
  if (invalid) ++counters_.invalid_inputs;

  // Reference generators.
  const std::int64_t clamps_before = roll_ref_.setpoint_clamp_count() + pitch_ref_.setpoint_clamp_count();
  const ReferenceState& rr = roll_ref_.step(roll_sp);
  const ReferenceState& pr = pitch_ref_.step(pitch_sp);
  counters_.setpoint_clamps += roll_ref_.setpoint_clamp_count() + pitch_ref_.setpoint_clamp_count() - clamps_before;
  out.roll_ref_rad = rr.angle_rad;
  out.roll_rate_ref_radps = rr.rate_radps;
  out.pitch_ref_rad = pr.angle_rad;
  out.pitch_rate_ref_radps = pr.rate_radps;
  out.roll_error_rad = rr.angle_rad - phi;
  out.pitch_error_rad = pr.angle_rad - theta;
  out.roll_kp_per_rad = gains_.kp_per_rad;
  out.roll_kd_per_radps = gains_.kd_per_radps;

  // PD loops, low-pass, saturation.
  const double roll_pd = gains_.kp_per_rad * out.roll_error_rad + gains_.kd_per_radps * (rr.rate_radps - p);
  const double pitch_pd =
      config_.pitch_gains.kp_per_rad * out.pitch_error_rad + config_.pitch_gains.kd_per_radps * (pr.rate_radps - q);
  const double roll_f = roll_lp_.step(roll_pd);
  const double pitch_f = pitch_lp_.step(pitch_pd);
  bool saturated = false;
  out.roll_cmd_norm = std::clamp(roll_f, -1.0, 1.0);
  if (out.roll_cmd_norm != roll_f) {
    ++counters_.roll_saturations;
    saturated = true;
  }
  out.pitch_cmd_norm = std::clamp(pitch_f, -1.0, 1.0);
  if (out.pitch_cmd_norm != pitch_f) {
    ++counters_.pitch_saturations;
    saturated = true;
  }

  // Throttle with tilt compensation: THRF in [1, 1/cos(roll set-point limit)].
  const double factor_max = 1.0 / std::cos(config_.roll_reference.setpoint_max_rad);
  const double factor = std::clamp(factor_in, 1.0, factor_max);
  const double throttle_sp = std::isfinite(in.throttle_pct) ? in.throttle_pct : config_.trim_throttle_pct;
  const double throttle_raw = throttle_sp * factor;
  out.throttle_cmd_pct = std::clamp(throttle_raw, 0.0, 100.0);
  if (factor != factor_in || out.throttle_cmd_pct != throttle_raw) {
    ++counters_.throttle_saturations;
    saturated = true;
  }
  out.delta_throttle_pct = out.throttle_cmd_pct - config_.trim_throttle_pct;

  // Mixing to flapping-frequency commands.
  const double k = config_.roll_cmd_to_delta_f_radps;
  const double f_collective = config_.f_trim_radps + config_.throttle_to_freq_radps_per_pct * out.delta_throttle_pct;
  const double delta_f = k * out.roll_cmd_norm;
  const double abs_term = k * config_.mix_abs_roll_gain * std::fabs(out.roll_cmd_norm);
  const double left_raw = f_collective + 0.5 * delta_f + abs_term;
  const double right_raw = f_collective - 0.5 * delta_f + abs_term;
  out.flap_freq_left_radps = std::clamp(left_raw, config_.flap_freq_min_radps, config_.flap_freq_max_radps);
  out.flap_freq_right_radps = std::clamp(right_raw, config_.flap_freq_min_radps, config_.flap_freq_max_radps);
  if (out.flap_freq_left_radps != left_raw || out.flap_freq_right_radps != right_raw) {
    ++counters_.flap_freq_saturations;
    saturated = true;
  }
  out.delta_f_cmd_radps = out.flap_freq_left_radps - out.flap_freq_right_radps;
  out.collective_radps = 0.5 * (out.flap_freq_left_radps + out.flap_freq_right_radps);
  out.dihedral_rad = config_.pitch_cmd_to_dihedral_rad * out.pitch_cmd_norm;
  // Yaw: hold the heading the run starts from (psi = 0), error wrapped to [-pi, pi].
  if (config_.yaw_enabled) {
    const double yaw_error = std::remainder(-psi, 2.0 * M_PI);
    const double yaw_f = yaw_lp_.step(config_.yaw_gains.kp_per_rad * yaw_error - config_.yaw_gains.kd_per_radps * r);
    out.yaw_cmd_norm = std::clamp(yaw_f, -1.0, 1.0);
    if (out.yaw_cmd_norm != yaw_f) {
      ++counters_.yaw_saturations;
      saturated = true;
    }
  }
  out.wing_root_rad = config_.yaw_cmd_to_wing_root_rad * out.yaw_cmd_norm;

  out.saturated = saturated;
  if (saturated) ++counters_.saturated_steps;
  return out;
}

ControllerOutput AttitudeController::failsafe_output(double throttle_pct) {
  reset();
  ControllerOutput out;
  out.throttle_cmd_pct = std::clamp(throttle_pct, 0.0, 100.0);
  out.delta_throttle_pct = out.throttle_cmd_pct - config_.trim_throttle_pct;
  const double f = std::clamp(config_.f_trim_radps + config_.throttle_to_freq_radps_per_pct * out.delta_throttle_pct,
                              config_.flap_freq_min_radps, config_.flap_freq_max_radps);
  out.flap_freq_left_radps = f;
  out.flap_freq_right_radps = f;
  out.collective_radps = f;
  out.delta_f_cmd_radps = 0.0;
  out.dihedral_rad = 0.0;
  out.wing_root_rad = 0.0;
  return out;
}

}  // namespace nimble
