#pragma once
/// How the plant flies the `effects:` section of a derivative model (written by
/// `rig discrepancy --model-out`, core/model.h DerivativeModel::effects), in one place.
///
/// Every effect name a model may carry (core/model.cc model_effect_names()) is handled, in the
/// regressor form the discrepancy workflow defines (ident/discrepancy.cc, kLibrary and
/// candidate_columns()), with the model's coefficients. The model's section overrides the
/// plant file's effect of the same name; a coefficient the section does not carry is 0.
///
///   effect                  parameters                         the plant flies
///   lateral_inflow          L_vv, Y_vv                         effects.lateral_inflow: L, Y += c v|v|
///   forward_speed_coupling  L_up, L_uv, Y_up, Y_uv             effects.forward_speed_coupling, four-
///                                                              coefficient form: L += L_up (u - u0) p
///                                                              + L_uv (u - u0) v, Y likewise
///   actuator_delay          delay_s (required; the regression's effects.actuator_delay: pure command
///                           <eq>_df_delayed, <eq>_df_fraction_  delay of delay_s
///                           delayed, <eq>_cmd_delayed are
///                           accepted and not needed)
///   flapping_forcing        flapping_hz, <eq>_sin<h>,          effects.flapping_forcing: amplitude
///                           <eq>_cos<h> (<eq>_amp<h>) for       hypot(sin_h, cos_h) at harmonic h of the
///                           eq L and Y                          plant's flapping phase, seeded phases
///   sensor_bias             L_0, Y_0                           effects.constant_load: constant roll
///                                                              moment L_0 and side force Y_0
///   dihedral_coupling       L_dd, Y_dd                         the dihedral derivatives L_dd, Y_dd
///   yaw_coupling            Lr, Yr                             the yaw-rate derivatives Lr, Yr
///   lateral_gust            sigma_mps, tau_s (both required)   effects.lateral_gust (Gauss-Markov)
///   kinematic_coupling      Y_pw                               nothing to add: the equations of
///   gravity_nonlinearity    Y_gphi                             motion carry p w and g sin(phi) exactly
///                                                              (effects_in_equations_of_motion())

#include <map>
#include <string>
#include <vector>

#include "core/model.h"
#include "plant/plant_model.h"

namespace nimble::plant {

/// Effects whose regressor is the part of the exact rigid-body equations that the linear model
/// (Eq 21) linearises: the plant's equations of motion (thesis Eq 3.1) already contain them
/// (kinematic_coupling: the p w term of v_dot; gravity_nonlinearity: g cos(theta) sin(phi)),
/// so a model carrying them needs nothing added. Their coefficient (the mass) is not used.
const std::vector<std::string>& effects_in_equations_of_motion();

/// Makes `effects` (the plant file's effects) and `derivatives` (the model's derivatives, as
/// the plant will fly them) fly every effect of `model.effects`, per the table above.
/// @throws std::invalid_argument naming the model (name and file), the effect and, where it
///         applies, the parameter: for an effect name the plant does not know, a parameter the
///         effect does not have, a non-finite or out-of-range value, a missing required
///         parameter (actuator_delay delay_s, lateral_gust sigma_mps and tau_s), or a
///         derivative (L_dd, Y_dd, Lr, Yr) that the model carries both among its derivatives
///         and in its effects.
void apply_model_effects(const DerivativeModel& model, EffectsConfig& effects,
                         std::map<std::string, double>& derivatives);

}  // namespace nimble::plant
