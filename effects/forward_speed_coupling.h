#pragma once
/// Forward-speed coupling, in one of two forms (not both: the reader and the PlantModel
/// constructor refuse a gain together with a coefficient):
///  - one gain k: the lateral stability derivatives (L, N and Y rows) scale with (1 + k (u - u0));
///  - four coefficients (the discrepancy workflow's regressors): L += L_up (u - u0) p +
///    L_uv (u - u0) v, Y += Y_up (u - u0) p + Y_uv (u - u0) v.
/// For a lateral3 model (r = 0, no N row) the gain k is the same as L_up = k Lp, L_uv = k Lv,
/// Y_up = k Yp, Y_uv = k Yv. u0 is the lateral model's trim; v is relative to the lateral gust,
/// as in the rest of the aerodynamics. u moves only with a longitudinal model (otherwise it is
/// held at trim and the effect is inert). Flies the model effect forward_speed_coupling in the
/// four-coefficient form.

#include <memory>

#include "core/config.h"
#include "core/param_table.h"
#include "effects/effect_process.h"
#include "effects/effect_sizing.h"
#include "effects/model_section.h"
#include "effects/effect.h"

namespace nimble::effects {

struct ForwardSpeedCouplingConfig {
  bool enabled = false;
  double gain_per_mps = 0.0;  ///< k [1/(m/s)]
  double L_up_ns2 = 0.0;      ///< [N m per (m/s) (rad/s)] = [N s^2]
  double L_uv_ns2pm = 0.0;    ///< [N m per (m/s)^2] = [N s^2/m]
  double Y_up_ns2pm = 0.0;    ///< [N per (m/s) (rad/s)] = [N s^2/m]
  double Y_uv_ns2pm2 = 0.0;   ///< [N per (m/s)^2] = [N s^2/m^2]
  /// True when any of the four coefficients is non-zero.
  bool has_coefficients() const {
    return L_up_ns2 != 0.0 || L_uv_ns2pm != 0.0 || Y_up_ns2pm != 0.0 || Y_uv_ns2pm2 != 0.0;
  }
};

/// `plant.effects.forward_speed_coupling`: key, range, unit, meaning.
const ParamTable<ForwardSpeedCouplingConfig>& forward_speed_coupling_params();

/// Reads the section (enabled is required; the gain or the coefficients, not both).
/// @throws ConfigError naming the key.
ForwardSpeedCouplingConfig forward_speed_coupling_from(ConfigMap& map);

/// The model effect forward_speed_coupling (L_up, L_uv, Y_up, Y_uv), replacing the gain.
void forward_speed_coupling_from_model(const ModelSection& section, ForwardSpeedCouplingConfig& config);

/// The factor on the lateral stability derivatives at forward-speed perturbation `du` [m/s].
inline double forward_speed_factor(const ForwardSpeedCouplingConfig& c, double du) {
  return c.enabled ? 1.0 + c.gain_per_mps * du : 1.0;
}

/// Adds the four-coefficient terms at `du` [m/s], roll rate `p` and relative side velocity `v_rel`.
inline void add_forward_speed_coupling(const ForwardSpeedCouplingConfig& c, double du, double p, double v_rel,
                                       double& L, double& Y) {
  if (!c.enabled) return;
  L += c.L_up_ns2 * du * p + c.L_uv_ns2pm * du * v_rel;
  Y += c.Y_up_ns2pm * du * p + c.Y_uv_ns2pm2 * du * v_rel;
}

/// The effect's process: the factor on the stability derivatives and the four-coefficient loads;
/// none when it is off.
/// @throws std::invalid_argument for a gain together with a coefficient (a model's effect
///         replaces the gain, so this is a plant file that gives both).
std::unique_ptr<EffectProcess> forward_speed_coupling_process(const ForwardSpeedCouplingConfig& config);

/// SIZE sets gain_per_mps; the explicit coefficients stay as set.
EffectSizing forward_speed_coupling_sizing();

/// The effect's definition, its mapping from a model and its plant section (registry.h).
Effect forward_speed_coupling_effect();

}  // namespace nimble::effects
