#include "core/effects.h"

#include <utility>

namespace nimble {

namespace {

/// The effects of the equations' form: terms the linear model leaves out, and the inputs and
/// states it does not carry.
std::vector<EffectSpec> form_effects() {
  return {
      {"kinematic_coupling",
       "p (w - w0): the vertical-velocity part of the kinematic term p w of v_dot that Eq 21 "
       "linearises at w0 (coefficient the mass)",
       {"w"},
       {{"Y", "Y_pw", "p (w - w0)"}},
       false,
       false,
       false,
       "nothing to add: the plant's equations of motion carry p w exactly"},
      {"gravity_nonlinearity",
       "g (sin phi - phi) cos theta0: the part of the gravity component that Eq 21 linearises "
       "(coefficient the mass)",
       {},
       {{"Y", "Y_gphi", "g (sin phi - phi) cos theta0"}},
       false,
       false,
       false,
       "nothing to add: the plant's equations of motion carry g cos(theta) sin(phi) exactly"},
      {"lateral_inflow",
       "v|v| in side force and roll moment: lateral inflow on the leading-edge vortex in sideways "
       "flight (plant effect lateral_inflow)",
       {},
       {{"L", "L_vv", "v|v|"}, {"Y", "Y_vv", "v|v|"}},
       false,
       false,
       false,
       "effects.lateral_inflow: L, Y += c v|v|"},
      {"forward_speed_coupling",
       "(u - u0) p and (u - u0) v: the lateral stability derivatives change with forward speed "
       "(plant effect forward_speed_coupling)",
       {"u"},
       {{"L", "L_up", "(u - u0) p"},
        {"L", "L_uv", "(u - u0) v"},
        {"Y", "Y_up", "(u - u0) p"},
        {"Y", "Y_uv", "(u - u0) v"}},
       false,
       false,
       false,
       "effects.forward_speed_coupling, four-coefficient form: L += L_up (u - u0) p + L_uv (u - u0) v, Y likewise"},
      {"actuator_delay",
       "delta_f(t - tau) - delta_f(t): the flap input acts tau later than recorded, tau scanned "
       "over 1 sample .. delay_max_s (plant effect actuator_delay)",
       {},
       {{"L", "L_df_delayed", "delta_f(t - tau) - delta_f(t)"},
        {"Y", "Y_df_delayed", "delta_f(t - tau) - delta_f(t)"},
        {"F", "F_cmd_delayed", "delta_f_cmd(t - t0 - tau) - delta_f_cmd(t - t0), t0 the command latency"}},
       true,
       false,
       false,
       "effects.actuator_delay: pure command delay of delay_s"},
      {"sensor_bias",
       "constant in both equations from a biased measurement: the rate gyro's p carries a constant "
       "offset, which the kinematics show (p against phi's derivative)",
       {},
       {{"L", "L_0", "1"}, {"Y", "Y_0", "1"}},
       false,
       false,
       false,
       "effects.constant_load: constant roll moment L_0 and side force Y_0"},
      {"constant_load",
       "a constant roll moment and side force (an offset trim: an asymmetric mass or wing) with "
       "no bias of the rate gyro (p agrees with phi's derivative)",
       {},
       {{"L", "L_0", "1"}, {"Y", "Y_0", "1"}},
       false,
       false,
       false,
       "effects.constant_load: constant roll moment L_0 and side force Y_0"},
      {"dihedral_coupling",
       "delta_d in roll moment and side force: the dihedral input the 3-state model leaves out",
       {"delta_d"},
       {{"L", "L_dd", "delta_d"}, {"Y", "Y_dd", "delta_d"}},
       false,
       false,
       false,
       "the dihedral derivatives L_dd, Y_dd"},
      {"yaw_coupling",
       "r in roll moment and side force: the yaw rate the 3-state model leaves out",
       {"r"},
       {{"L", "Lr", "r"}, {"Y", "Yr", "r"}},
       false,
       false,
       false,
       "the yaw-rate derivatives Lr, Yr (inert on a lateral3 model: r held at trim)"},
  };
}

/// The effects that change over the flight or come from a process: drifts and steps of the flap
/// input's effectiveness, the flapping forcing, the side gust.
std::vector<EffectSpec> time_and_process_effects() {
  return {
      {"effectiveness_drift",
       "(t - t_mid) delta_f in roll moment and side force: the flap input's effectiveness drifts over the "
       "flight (battery sag), named with its rate as a fraction of L_df per minute (plant effect "
       "effectiveness_drift)",
       {},
       {{"L", "L_df_rate", "(t - t_mid) delta_f"}, {"Y", "Y_df_rate", "(t - t_mid) delta_f"}},
       false,
       false,
       false,
       "effects.effectiveness_drift: L_df, Y_df x (1 + rate_per_min (t - t_ref) / 60)"},
      {"effectiveness_step",
       "H(t - t*) delta_f in roll moment and side force: the flap input's effectiveness changes at an "
       "unknown time t* (a damaged wing), t* scanned over the record away from its ends, named with "
       "t_change_s and the fractional change (plant effect effectiveness_step)",
       {},
       {{"L", "L_df_step", "H(t - t*) delta_f"}, {"Y", "Y_df_step", "H(t - t*) delta_f"}},
       true,
       false,
       false,
       "effects.effectiveness_step: L_df x (1 + roll_fraction), Y_df x (1 + side_fraction) from t_change_s on"},
      {"flapping_forcing",
       "sin and cos of h 2 pi f t (h = 1, 2) in roll moment and side force: periodic forcing at the flapping "
       "frequency f, scanned over 10-25 Hz on data low-passed above the band (plant effect flapping_forcing)",
       {},
       {{"L", "L_sin1", "sin(2 pi f t)"},
        {"L", "L_cos1", "cos(2 pi f t)"},
        {"L", "L_sin2", "sin(4 pi f t)"},
        {"L", "L_cos2", "cos(4 pi f t)"},
        {"Y", "Y_sin1", "sin(2 pi f t)"},
        {"Y", "Y_cos1", "cos(2 pi f t)"},
        {"Y", "Y_sin2", "sin(4 pi f t)"},
        {"Y", "Y_cos2", "cos(4 pi f t)"}},
       true,
       true,
       false,
       "effects.flapping_forcing: amplitude hypot(sin_h, cos_h) at harmonic h of the plant's flapping phase"},
      {"lateral_gust",
       "an unmeasured side wind v_g: the aerodynamics see v - v_g, so the side-force equation carries "
       "-Yv v_g, a low-frequency random force. Stochastic, no regressor: named from its signature in the "
       "residual spectrum (plant effect lateral_gust; parameters sigma_mps, tau_s)",
       {},
       {},
       false,
       false,
       true,
       "effects.lateral_gust (Gauss-Markov, sigma_mps and tau_s)"},
  };
}

}  // namespace

const std::vector<EffectSpec>& effect_registry() {
  static const std::vector<EffectSpec> registry = [] {
    std::vector<EffectSpec> all = form_effects();
    for (auto& e : time_and_process_effects()) all.push_back(std::move(e));
    return all;
  }();
  return registry;
}

const EffectSpec* find_effect(const std::string& name) {
  for (const auto& e : effect_registry()) {
    if (e.name == name) return &e;
  }
  return nullptr;
}

std::string effect_name_list() {
  std::string list;
  for (const auto& e : effect_registry()) list += (list.empty() ? "" : ", ") + e.name;
  return list;
}

}  // namespace nimble
