#pragma once
/// How one number sizes a plant effect (`rig discrepancy --power --effect NAME=SIZE`, detection_power/):
/// SIZE is the value of the effect's main parameter, in that parameter's unit and range, and
/// the effect's other values keep the shape the scenario gives them. Each sizable effect
/// declares its sizing in its own file; the registry (registry.h) carries it.

#include <string>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "core/config.h"

namespace nimble::effects {

/// One key under plant.effects.<effect>. and its value as YAML text.
using EffectValue = std::pair<std::string, std::string>;

struct EffectSizing {
  std::string parameter;  ///< the key SIZE sets ("": the effect is not sized by one number)
  std::string unit;
  Range range;         ///< of SIZE (the parameter's range in the effect's table)
  std::string scales;  ///< what else SIZE moves (help text)
  /// The values that fly the effect at `size` (not 0), given the scenario's section of the
  /// effect (`section`, null if it has none): the parameter and every companion it scales.
  /// @throws std::invalid_argument naming the problem (a companion that leaves its range, a
  ///         shape with nothing to scale from).
  std::vector<EffectValue> (*values)(const YAML::Node& section, double size) = nullptr;
};

/// The section's number `key`, or `fallback` if it has none.
double section_number(const YAML::Node& section, const std::string& key, double fallback);

/// The section's list `key` (empty if it has none).
std::vector<double> section_list(const YAML::Node& section, const std::string& key);

/// `value` of companion `key` if it is within `range`.
/// @throws std::invalid_argument "the scenario's ratio makes <key> <value>, not <range>".
double companion_within(const std::string& key, double value, const Range& range);

/// The values that fly an effect at `size` whose `companion` keeps its ratio to `parameter` as
/// the scenario's section gives them (`ratio_if_zero` where the section's parameter is 0 or absent).
/// @throws std::invalid_argument (companion_within()) if the companion leaves `companion_range`.
std::vector<EffectValue> with_companion_ratio(const YAML::Node& section, double size, const std::string& parameter,
                                              const std::string& companion, const Range& companion_range,
                                              double ratio_if_zero);

/// The sizing of an effect whose SIZE sets `parameter` alone.
std::vector<EffectValue> parameter_alone(const std::string& parameter, double size);

}  // namespace nimble::effects
