#pragma once
/// The plant's effect registry: each plant effect (one file in this folder) with its section
/// reader, its parameter table and the registry effects (core/effects.h) it flies from a
/// model's `effects:` section; and the effects a model may carry that the plant flies as
/// derivatives or already has in its equations of motion. The scenario loader, the PlantModel
/// constructor and `rig params plant.effects` read it. Adding an effect: README.md here.

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/model.h"
#include "plant/effects/effect_process.h"
#include "plant/effects/effect_sizing.h"
#include "plant/effects/effects_config.h"
#include "plant/effects/model_section.h"

namespace nimble::plant {

/// One plant effect: `plant.effects.<name>`.
struct PlantEffect {
  std::string name;
  /// Reads its section into `effects`. @throws ConfigError naming the key.
  void (*load)(ConfigMap& section, EffectsConfig& effects);
  /// Its parameters as Markdown rows (key, default, allowed, unit, meaning), keys after `prefix`.
  std::string (*markdown_rows)(const std::string& prefix);
  /// The registry effect (core/effects.h) a model's effects: section names for it, or "".
  std::string model_effect;
  /// Sets `effects` from that section of a model. @throws std::invalid_argument naming the
  /// model, the effect and the parameter.
  void (*from_model)(const ModelSection& section, EffectsConfig& effects);
  /// Its process while the plant flies (effect_process.h: on the commands, the side wind, the
  /// stability derivatives, the loads, with its state), or none when the effect does nothing
  /// in `effects`. The plant makes every effect's process, in this list's order, when it is made.
  /// @throws std::invalid_argument for a configuration the effect cannot fly.
  std::unique_ptr<EffectProcess> (*make)(const EffectsConfig& effects, ProcessContext& context);
  /// True if the effect is on in `effects` (what `rig loop` names as left out of its linear loop).
  bool (*enabled)(const EffectsConfig& effects);
  /// What one number SIZE sets (effect_sizing.h: `rig discrepancy --power`), or nullptr for an
  /// effect that is not sized by one number.
  EffectSizing (*sizing)();
  /// True if its process acts only on the commands, which the linear loop of `rig loop` models
  /// as a delay (so `rig loop` does not name it as left out).
  bool in_linear_loop = false;
};

/// Every plant effect, in the order the plant makes their processes and calls their hooks
/// (PlantModel::derivative()).
const std::vector<PlantEffect>& plant_effects();

/// The processes of every effect that acts in `effects`, in plant_effects()'s order.
/// @throws std::invalid_argument naming the effect whose configuration cannot fly.
std::vector<std::unique_ptr<EffectProcess>> make_effect_processes(const EffectsConfig& effects,
                                                                  ProcessContext& context);

/// Reads the `effects` section of the plant: every key one of plant_effects().
/// @throws ConfigError naming the key (an unknown effect names the known ones).
void effects_from(ConfigMap& section, EffectsConfig& effects);

/// `rig params plant.effects`: every plant effect's parameters as one Markdown table.
std::string effects_markdown();

/// Effects whose regressor is the part of the exact rigid-body equations that the linear model
/// (Eq 21) linearises: the plant's equations of motion (thesis Eq 3.1) already contain them
/// (kinematic_coupling: the p w term of v_dot; gravity_nonlinearity: g cos(theta) sin(phi)),
/// so a model carrying them needs nothing added. Their coefficient (the mass) is not used.
const std::vector<std::string>& effects_in_equations_of_motion();

/// Makes `effects` (the plant file's effects) and `derivatives` (the model's derivatives, as
/// the plant will fly them) fly every effect of `model.effects`: a plant effect through its
/// from_model (overriding the plant file's effect of the same name; a coefficient the section
/// does not carry is 0), dihedral_coupling (L_dd, Y_dd) and yaw_coupling (Lr, Yr) as
/// derivatives, the effects of effects_in_equations_of_motion() by nothing.
/// @throws std::invalid_argument naming the model (name and file), the effect and, where it
///         applies, the parameter: for an effect name the plant does not know, a parameter the
///         effect does not have, a non-finite or out-of-range value, a missing required
///         parameter, or a derivative that the model carries both among its derivatives and in
///         its effects.
void apply_model_effects(const DerivativeModel& model, EffectsConfig& effects,
                         std::map<std::string, double>& derivatives);

}  // namespace nimble::plant
