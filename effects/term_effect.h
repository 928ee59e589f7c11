#pragma once
/// The plant's side of an effect whose every column is a term of the grammar
/// (core/term_expression.h): its `plant.effects.<name>` section is `enabled` and one
/// coefficient per column, keyed as the model's effects: section keys it (one set of keys),
/// with the column's unit and range; the plant flies it as those terms (PlantModel's generic
/// terms, in the plant's signals). Such an effect needs no process and no code of its own in
/// the plant: its file pair gives its definition and term_effect() makes the rest.

#include <map>
#include <string>

#include "effects/effect.h"

namespace nimble::effects {

/// The coefficients of every term effect that is on, by effect name, then parameter name.
struct TermEffectsConfig {
  std::map<std::string, std::map<std::string, double>> on;
};

/// The effect of `definition` (every column kTerm) with its plant side made from the columns.
/// @throws std::logic_error for a column that is not a term or does not parse.
Effect term_effect(EffectDefinition definition);

}  // namespace nimble::effects
