#pragma once
/// Effectiveness step: from t_change_s on, the roll input's effectiveness changes by a fraction,
/// L_df x (1 + roll_fraction) and Y_df x (1 + side_fraction) (a damaged wing: a torn or bent
/// wing on one side produces less of the differential thrust the flap-frequency difference
/// commands). Flies the model effect effectiveness_step (L_df_step, Y_df_step: the coefficients
/// of H(t - t_change) delta_f, with the model's L_df and Y_df the values before the change).

#include "core/config.h"
#include "core/param_table.h"
#include "effects/model_section.h"
#include "effects/effect.h"

namespace nimble::effects {

struct EffectivenessStepConfig {
  bool enabled = false;
  double t_change_s = 0.0;     ///< time of the change [s]
  double roll_fraction = 0.0;  ///< L_df changes by this fraction [-]
  double side_fraction = 0.0;  ///< Y_df changes by this fraction [-]
};

/// `plant.effects.effectiveness_step`: key, range, unit, meaning.
const ParamTable<EffectivenessStepConfig>& effectiveness_step_params();

/// Reads the section (enabled is required). @throws ConfigError naming the key.
EffectivenessStepConfig effectiveness_step_from(ConfigMap& map);

/// The model effect effectiveness_step: t_change_s (required), roll_fraction = L_df_step / L_df
/// and side_fraction = Y_df_step / Y_df of the model (0 for a coefficient the section does not
/// carry); the reported intervals and fractions are accepted and not needed.
void effectiveness_step_from_model(const ModelSection& section, EffectivenessStepConfig& config);

/// Adds the change of the roll input's moment and force at time `t_s` [s]: `roll_input_nm` =
/// L_df delta_f and `roll_input_n` = Y_df delta_f of the derivative model.
inline void add_effectiveness_step(const EffectivenessStepConfig& c, double t_s, double roll_input_nm,
                                   double roll_input_n, double& L, double& Y) {
  if (!c.enabled || t_s < c.t_change_s) return;
  L += c.roll_fraction * roll_input_nm;
  Y += c.side_fraction * roll_input_n;
}

/// The effect's definition, its mapping from a model and its plant section (registry.h).
Effect effectiveness_step_effect();

}  // namespace nimble::effects
