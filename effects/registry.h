#pragma once
/// The registry of the effects beyond the paper's linear model: one list, each entry one
/// effect's file pair (effect.h), in a fixed order. A model file's `effects:` section, the
/// plant (its `plant.effects` sections, its processes, its terms), the discrepancy workflow's
/// candidate library, `rig params plant.effects`, `rig loop`, `rig turbulence-response`,
/// `rig discrepancy --power` and the command-line help all read it, and none of them names an
/// effect of its own. Adding an effect: README.md here.

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/config.h"
#include "core/model.h"
#include "effects/effect.h"

namespace nimble::effects {

/// Every effect, in the registry's order: the order of the discrepancy workflow's library and
/// the order in which the plant makes the processes and adds the loads of those it flies.
const std::vector<Effect>& effect_registry();

/// The effect called `name`, or nullptr.
const Effect* find_effect(const std::string& name);

/// The definition of the effect called `name`, or nullptr.
const EffectDefinition* find_definition(const std::string& name);

/// The effects' names, in the registry's order, joined by ", " (help texts, error messages).
std::string effect_name_list();

/// Every effect with a `plant.effects.<name>` section, in the registry's order.
std::vector<const Effect*> plant_effects();

/// The processes of every effect that acts in `effects`, in the registry's order.
/// @throws std::invalid_argument naming the effect whose configuration cannot fly.
std::vector<std::unique_ptr<EffectProcess>> make_effect_processes(const EffectsConfig& effects,
                                                                  ProcessContext& context);

/// The terms the term effects on in `effects` add to the plant's loads, in the registry's order,
/// with `trim` (the plant's) put for u0 and w0.
std::vector<Term> effect_terms(const EffectsConfig& effects, const Trim& trim);

/// Reads the `effects` section of the plant: every key one of plant_effects().
/// @throws ConfigError naming the key (an unknown effect names the known ones).
void effects_from(ConfigMap& section, EffectsConfig& effects);

/// `rig params plant.effects`: every plant effect's parameters as one Markdown table.
std::string effects_markdown();

/// Refuses an effect of `model.effects` that the registry does not know.
/// @throws std::invalid_argument naming the model (name and file), the effect and the known ones.
void check_model_effects(const DerivativeModel& model);

/// Makes `effects` (the plant file's effects) and `derivatives` (the model's derivatives, as
/// the plant will fly them) fly every effect of `model.effects`, each through its from_model
/// (overriding the plant file's effect of the same name; a coefficient the section does not
/// carry is 0).
/// @throws std::invalid_argument naming the model (name and file), the effect and, where it
///         applies, the parameter: for an effect name the registry does not know, a parameter
///         the effect does not have, a non-finite or out-of-range value, a missing required
///         parameter, or a derivative that the model carries both among its derivatives and in
///         its effects.
void apply_model_effects(const DerivativeModel& model, EffectsConfig& effects,
                         std::map<std::string, double>& derivatives);

}  // namespace nimble::effects
