#include "plant/model_effects.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <stdexcept>

namespace nimble::plant {
namespace {

using Params = std::map<std::string, double>;

/// Harmonics of flapping_forcing the plant accepts from a model (the workflow fits 2).
constexpr int kMaxHarmonics = 10;

/// The effect section being read, for error messages.
struct Section {
  const DerivativeModel& model;
  const std::string& effect;
  const Params& params;

  std::string where() const {
    return "plant: model '" + model.name + "'" + (model.file.empty() ? "" : " (" + model.file + ")") +
           ", effects." + effect;
  }
  [[noreturn]] void fail(const std::string& problem) const { throw std::invalid_argument(where() + ": " + problem); }
  [[noreturn]] void fail(const std::string& key, const std::string& problem) const {
    throw std::invalid_argument(where() + "." + key + ": " + problem);
  }

  /// Refuses a parameter `known` does not accept, and non-finite values.
  void check_keys(const std::function<bool(const std::string&)>& known, const std::string& expected) const {
    for (const auto& [key, value] : params) {
      if (!known(key)) fail(key, "not a parameter of " + effect + " (expected " + expected + ")");
      if (!std::isfinite(value)) fail(key, "must be finite");
    }
  }
  void check_keys(const std::vector<std::string>& names) const {
    std::string list;
    for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
    check_keys([&](const std::string& k) { return std::find(names.begin(), names.end(), k) != names.end(); }, list);
  }

  /// The value of `key`, 0 if the section does not carry it; refused outside [lo, hi].
  double or_zero(const std::string& key, double lo, double hi) const {
    const auto it = params.find(key);
    if (it == params.end()) return 0.0;
    in_range(key, it->second, lo, hi);
    return it->second;
  }
  /// The value of `key`, which the section must carry; refused outside [lo, hi].
  double required(const std::string& key, double lo, double hi) const {
    const auto it = params.find(key);
    if (it == params.end()) fail("needs the parameter " + key);
    in_range(key, it->second, lo, hi);
    return it->second;
  }
  void in_range(const std::string& key, double value, double lo, double hi) const {
    if (!(value >= lo && value <= hi)) {
      fail(key, std::to_string(value) + " is outside [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    }
  }
};

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() > suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// Parses "<eq>_<kind><h>" (e.g. "L_sin2") for eq L or Y, kind sin, cos or amp, h 1..kMaxHarmonics.
bool parse_harmonic(const std::string& key, char* eq, std::string* kind, int* h) {
  if (key.size() < 6 || (key[0] != 'L' && key[0] != 'Y') || key[1] != '_') return false;
  const std::string k = key.substr(2, 3);
  if (k != "sin" && k != "cos" && k != "amp") return false;
  const std::string digits = key.substr(5);
  if (digits.empty() || digits.size() > 2 || digits[0] == '0' ||
      !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    return false;
  }
  const int n = std::stoi(digits);
  if (n < 1 || n > kMaxHarmonics) return false;
  *eq = key[0];
  *kind = k;
  *h = n;
  return true;
}

/// Amplitudes per harmonic of equation `eq`: hypot(sin_h, cos_h) where the section carries
/// either, otherwise <eq>_amp<h> (the workflow writes it as that same hypot), otherwise 0; as
/// many harmonics as the highest one the section names for `eq`.
std::vector<double> harmonic_amplitudes(const Section& s, char eq) {
  std::map<int, double> sin_of, cos_of, amp_of;
  int highest = 0;
  for (const auto& [key, value] : s.params) {
    char e;
    std::string kind;
    int h;
    if (!parse_harmonic(key, &e, &kind, &h) || e != eq) continue;
    (kind == "sin" ? sin_of : kind == "cos" ? cos_of : amp_of)[h] = value;
    highest = std::max(highest, h);
  }
  std::vector<double> out;
  for (int h = 1; h <= highest; ++h) {
    double a = 0.0;
    if (sin_of.count(h) || cos_of.count(h)) {
      a = std::hypot(sin_of.count(h) ? sin_of[h] : 0.0, cos_of.count(h) ? cos_of[h] : 0.0);
    } else if (amp_of.count(h)) {
      a = std::fabs(amp_of[h]);
    }
    if (a > 1.0) {
      s.fail("harmonic " + std::to_string(h) + " of " + std::string(1, eq) + " has amplitude " + std::to_string(a) +
             ", more than 1 (N or N m), which the plant file's amplitudes may not exceed either");
    }
    out.push_back(a);
  }
  return out;
}

/// Sets derivative `name` from the section (a coefficient the section does not carry is left
/// as the model has it). Refuses one the model also carries among its derivatives: the two
/// would be two values of one term.
void set_derivative(const Section& s, const std::string& name, std::map<std::string, double>& derivatives,
                    double lo, double hi) {
  const auto it = s.params.find(name);
  if (it == s.params.end()) return;
  if (s.model.derivatives.count(name)) {
    s.fail(name, "the model also carries " + name + " among its derivatives; give it in one place only");
  }
  s.in_range(name, it->second, lo, hi);
  derivatives[name] = it->second;
}

}  // namespace

const std::vector<std::string>& effects_in_equations_of_motion() {
  static const std::vector<std::string> names{"kinematic_coupling", "gravity_nonlinearity"};
  return names;
}

void apply_model_effects(const DerivativeModel& model, EffectsConfig& fx, std::map<std::string, double>& derivatives) {
  // Bounds: those of the plant file's keys where the plant file has the effect, otherwise
  // wide sanity bounds (|L| terms up to 0.1 N m per unit, |Y| terms up to 1 N per unit).
  for (const auto& [name, params] : model.effects) {
    const Section s{model, name, params};

    if (name == "lateral_inflow") {
      // L += L_vv v|v|, Y += Y_vv v|v| (v relative to the gust).
      s.check_keys({"L_vv", "Y_vv"});
      auto& li = fx.lateral_inflow;
      li.enabled = true;
      li.L_vv_ns2pm = s.or_zero("L_vv", -0.1, 0.1);
      li.Y_vv_ns2pm2 = s.or_zero("Y_vv", -1.0, 1.0);

    } else if (name == "forward_speed_coupling") {
      // The workflow's regressors (u - u0) p and (u - u0) v in L and Y: the plant's
      // four-coefficient form, replacing the plant file's gain.
      s.check_keys({"L_up", "L_uv", "Y_up", "Y_uv"});
      auto& fsc = fx.forward_speed_coupling;
      fsc.enabled = true;
      fsc.gain_per_mps = 0.0;
      fsc.L_up_ns2 = s.or_zero("L_up", -0.1, 0.1);
      fsc.L_uv_ns2pm = s.or_zero("L_uv", -0.1, 0.1);
      fsc.Y_up_ns2pm = s.or_zero("Y_up", -1.0, 1.0);
      fsc.Y_uv_ns2pm2 = s.or_zero("Y_uv", -1.0, 1.0);

    } else if (name == "actuator_delay") {
      // The workflow finds that delta_f acts delay_s later than recorded (regressor
      // delta_f(t - tau) - delta_f(t)). The plant flies it as its pure command delay: a pure
      // delay commutes with the linear flap actuator (delta_f = gain/(s + pole) delta_f_cmd), so
      // delaying the command is the same dynamics as delaying the actuator's output that the
      // aerodynamics see. The plant delays every command (the servos too) and all of the input
      // (the workflow names the effect only when most of it acts delayed); the regression's
      // coefficients of the delayed column, the delayed fractions and an actuator-equation
      // coefficient are accepted but not needed.
      s.check_keys(
          [](const std::string& k) {
            return k == "delay_s" || ends_with(k, "_df_delayed") || ends_with(k, "_df_fraction_delayed") ||
                   ends_with(k, "_cmd_delayed");
          },
          "delay_s, <eq>_df_delayed, <eq>_df_fraction_delayed, <eq>_cmd_delayed");
      auto& d = fx.actuator_delay;
      d.enabled = true;
      d.delay_s = s.required("delay_s", 0.0, 0.5);

    } else if (name == "flapping_forcing") {
      // The workflow regresses sin and cos of h 2 pi f t (h = 1, 2) at a fixed frequency f
      // (flapping_hz) found in the data. The plant flies harmonic h with amplitude
      // hypot(sin_h, cos_h) in roll moment and side force, phase-locked to its own flapping
      // phase: at h times the flapping frequency of the actual collective (about 16-17 Hz at
      // trim; it follows the throttle), not at flapping_hz. The phase relative to the flapping
      // phase is not identifiable from a fixed-frequency regression on a record with an
      // arbitrary time origin, so the plant keeps its seeded phases.
      s.check_keys(
          [](const std::string& k) {
            char e;
            std::string kind;
            int h;
            return k == "flapping_hz" || parse_harmonic(k, &e, &kind, &h);
          },
          "flapping_hz, <eq>_sin<h>, <eq>_cos<h>, <eq>_amp<h> for eq L or Y and h 1.." + std::to_string(kMaxHarmonics));
      auto& ff = fx.flapping_forcing;
      ff.enabled = true;
      ff.roll_moment_amplitudes_nm = harmonic_amplitudes(s, 'L');
      ff.side_force_amplitudes_n = harmonic_amplitudes(s, 'Y');

    } else if (name == "sensor_bias") {
      // Regressor 1 in L and Y: the plant flies a constant roll moment L_0 and side force Y_0
      // (the regression cannot tell a rate-sensor bias from a constant moment).
      s.check_keys({"L_0", "Y_0"});
      auto& c = fx.constant_load;
      c.enabled = true;
      c.roll_moment_nm = s.or_zero("L_0", -0.1, 0.1);
      c.side_force_n = s.or_zero("Y_0", -1.0, 1.0);

    } else if (name == "dihedral_coupling") {
      // Regressor delta_d in L and Y: the dihedral derivatives.
      s.check_keys({"L_dd", "Y_dd"});
      set_derivative(s, "L_dd", derivatives, -0.1, 0.1);
      set_derivative(s, "Y_dd", derivatives, -1.0, 1.0);

    } else if (name == "yaw_coupling") {
      // Regressor r in L and Y: the yaw-rate derivatives. They act only where r is a state
      // (a lateral4 model); with a lateral3 model the plant holds r at trim (0), as the
      // vehicle's yaw loop would, and they are inert.
      s.check_keys({"Lr", "Yr"});
      set_derivative(s, "Lr", derivatives, -0.1, 0.1);
      set_derivative(s, "Yr", derivatives, -1.0, 1.0);

    } else if (name == "lateral_gust") {
      // No regressor: named from the residual spectrum with the plant's first-order
      // Gauss-Markov parameters.
      s.check_keys({"sigma_mps", "tau_s"});
      auto& g = fx.lateral_gust;
      g.enabled = true;
      g.form = GustForm::kGaussMarkov;
      g.sigma_mps = s.required("sigma_mps", 0.0, 5.0);
      g.tau_s = s.required("tau_s", 1e-6, 100.0);

    } else if (name == "kinematic_coupling" || name == "gravity_nonlinearity") {
      // Nothing to add (effects_in_equations_of_motion()): Y_pw is the coefficient of
      // p (w - w0), the part of the kinematic term p w of v_dot that Eq 21 linearises at w0,
      // and Y_gphi that of g (sin phi - phi) cos theta0; the plant's equations of motion
      // (Eq 3.1) carry p w and g cos(theta) sin(phi) exactly, with the vehicle's mass.
      s.check_keys({name == "kinematic_coupling" ? "Y_pw" : "Y_gphi"});

    } else {
      std::string list;
      for (const auto& k : model_effect_names()) list += (list.empty() ? "" : ", ") + k;
      s.fail("effect '" + name + "' is not one the plant can fly (known: " + list + ")");
    }
  }
}

}  // namespace nimble::plant
