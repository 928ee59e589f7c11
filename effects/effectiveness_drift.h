#pragma once
/// Effectiveness drift: the roll input's effectiveness changes linearly over the flight, L_df and
/// Y_df scaled by 1 + rate_per_min (t - t_ref_s) / 60 (battery sag: the moment and side force per
/// unit of flap-frequency difference fall as the battery's voltage does). The scale is clamped at
/// 0 (never a reversed input). Flies the model effect effectiveness_drift (L_df_rate, Y_df_rate:
/// the coefficients of (t - t_mid) delta_f, with t_mid_s the time at which the model's L_df and
/// Y_df hold).

#include <algorithm>

#include "core/config.h"
#include "core/param_table.h"
#include "effects/model_section.h"
#include "effects/effect.h"

namespace nimble::effects {

struct EffectivenessDriftConfig {
  bool enabled = false;
  double rate_per_min = 0.0;  ///< fractional change of L_df and Y_df per minute [1/min]
  double t_ref_s = 0.0;       ///< time at which the scale is 1 (the model's L_df, Y_df hold) [s]
};

/// `plant.effects.effectiveness_drift`: key, range, unit, meaning.
const ParamTable<EffectivenessDriftConfig>& effectiveness_drift_params();

/// Reads the section (enabled is required). @throws ConfigError naming the key.
EffectivenessDriftConfig effectiveness_drift_from(ConfigMap& map);

/// The model effect effectiveness_drift: the rate from L_df_rate / L_df (or, without L_df_rate,
/// Y_df_rate / Y_df) of the model, per minute; t_ref_s from t_mid_s (0 without it). The plant flies
/// one rate for both (the roll equation's, as the named rate_per_min reports it); the reported
/// interval and rate_per_min are accepted and not needed.
void effectiveness_drift_from_model(const ModelSection& section, EffectivenessDriftConfig& config);

/// Adds the change of the roll input's moment and force at time `t_s` [s]: `roll_input_nm` =
/// L_df delta_f and `roll_input_n` = Y_df delta_f of the derivative model.
inline void add_effectiveness_drift(const EffectivenessDriftConfig& c, double t_s, double roll_input_nm,
                                    double roll_input_n, double& L, double& Y) {
  if (!c.enabled) return;
  const double change = std::max(-1.0, c.rate_per_min * (t_s - c.t_ref_s) / 60.0);
  L += change * roll_input_nm;
  Y += change * roll_input_n;
}

/// The effect's definition, its mapping from a model and its plant section (registry.h).
Effect effectiveness_drift_effect();

}  // namespace nimble::effects
