#pragma once
/// Constant roll moment and side force: L += L_0, Y += Y_0 (keys L_0, Y_0, as a model keys them). Flies the model
/// effect sensor_bias (L_0, Y_0): the equation-error regression cannot tell a rate-sensor bias
/// from a constant moment, and the plant flies the moment/force form.

#include "core/config.h"
#include "core/param_table.h"
#include "effects/effect_sizing.h"
#include "effects/model_section.h"
#include "effects/effect.h"

namespace nimble::effects {

struct ConstantLoadConfig {
  bool enabled = false;
  double roll_moment_nm = 0.0;  ///< [N m]
  double side_force_n = 0.0;    ///< [N]
};

/// `plant.effects.constant_load`: key, range, unit, meaning.
const ParamTable<ConstantLoadConfig>& constant_load_params();

/// Reads the section (enabled is required). @throws ConfigError naming the key.
ConstantLoadConfig constant_load_from(ConfigMap& map);

/// The model effect sensor_bias (L_0, Y_0).
void constant_load_from_model(const ModelSection& section, ConstantLoadConfig& config);

/// Adds the constant roll moment and side force.
inline void add_constant_load(const ConstantLoadConfig& c, double& L, double& Y) {
  if (!c.enabled) return;
  L += c.roll_moment_nm;
  Y += c.side_force_n;
}

/// SIZE sets L_0; Y_0 keeps its ratio to it (none if the scenario's moment is 0).
EffectSizing constant_load_sizing();

/// The effect's definition, its mapping from a model and its plant section (registry.h).
Effect constant_load_effect();

}  // namespace nimble::effects
