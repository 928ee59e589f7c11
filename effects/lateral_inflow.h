#pragma once
/// Lateral inflow: Y += Y_vv v|v|, L += L_vv v|v| (sideways flight, thesis §9.5), with v the
/// velocity relative to the lateral gust. Flies the model effect lateral_inflow (L_vv, Y_vv).

#include <cmath>

#include "core/config.h"
#include "core/param_table.h"
#include "effects/effect_sizing.h"
#include "effects/model_section.h"
#include "effects/effect.h"

namespace nimble::effects {

struct LateralInflowConfig {
  bool enabled = false;
  double Y_vv_ns2pm2 = 0.0;  ///< [N s^2/m^2]
  double L_vv_ns2pm = 0.0;   ///< [N m s^2/m^2]
};

/// `plant.effects.lateral_inflow`: key, range, unit, meaning (the defaults are the struct's).
const ParamTable<LateralInflowConfig>& lateral_inflow_params();

/// Reads the section (enabled is required). @throws ConfigError naming the key.
LateralInflowConfig lateral_inflow_from(ConfigMap& map);

/// The model effect lateral_inflow (L_vv, Y_vv; a coefficient it does not carry is 0).
void lateral_inflow_from_model(const ModelSection& section, LateralInflowConfig& config);

/// Adds the effect's roll moment and side force at relative side velocity `v_rel` [m/s].
inline void add_lateral_inflow(const LateralInflowConfig& c, double v_rel, double& L, double& Y) {
  if (!c.enabled) return;
  Y += c.Y_vv_ns2pm2 * v_rel * std::fabs(v_rel);
  L += c.L_vv_ns2pm * v_rel * std::fabs(v_rel);
}

/// SIZE sets Y_vv; L_vv keeps its ratio to it (0.01 m if the scenario's Y_vv is 0).
EffectSizing lateral_inflow_sizing();

/// The effect's definition, its mapping from a model and its plant section (registry.h).
Effect lateral_inflow_effect();

}  // namespace nimble::effects
