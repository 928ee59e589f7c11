#pragma once
/// The size of a plant effect, as `rig discrepancy --power --effect NAME=SIZE` takes it: one
/// number per plant effect (effects/), the value of its main plant parameter, in that
/// parameter's unit, within its range.
///
/// Each plant effect declares what its SIZE sets in its own file (`<name>_sizing()`,
/// effects/effect_sizing.h); `rig discrepancy --help` lists them. E.g. lateral_inflow:
/// SIZE sets Y_vv [N s^2/m^2] and L_vv keeps its ratio to Y_vv.
///
/// "Keeps its ratio": the scenario's own values (after its --set) fix the shape of the effect,
/// SIZE its scale: lateral inflow with SIZE -0.035 on a scenario that flies Y_vv -0.07 and
/// L_vv -7e-4 flies Y_vv -0.035 and L_vv -3.5e-4. Where the scenario's main value is 0 there is
/// no shape to keep: lateral_inflow takes the plant file's ratio (L_vv = 0.01 m Y_vv),
/// constant_load no side force; flapping_forcing needs a first roll amplitude to scale from.
/// SIZE 0 switches the effect off: the null case, whose naming rate is the false-naming rate.

#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "core/config.h"
#include "effects/effect_sizing.h"
#include "scenario/scenario.h"

namespace nimble::detection_power {

/// One plant effect that the power analysis can size.
struct SizedEffect {
  std::string effect;     ///< plant effect, plant.effects.<effect>
  std::string parameter;  ///< the key SIZE sets
  std::string unit;
  Range range;           ///< of SIZE (the parameter's range in the plant's table)
  std::string named_as;  ///< the name the discrepancy workflow gives it (effects/registry.h: the effect itself)
  std::string scales;    ///< what else SIZE moves (help text)
  /// The effect's values at a size (effects/effect_sizing.h).
  std::vector<effects::EffectValue> (*values)(const YAML::Node& section, double size) = nullptr;
};

/// Every sizable effect, in the plant registry's order.
const std::vector<SizedEffect>& sized_effects();

/// The sizable effect `effect`. @throws std::invalid_argument naming it and every effect with
/// its parameter and unit.
const SizedEffect& sized_effect(const std::string& effect);

/// "lateral_inflow=Y_vv [N s^2/m^2], ..." for help texts and errors.
std::string sized_effect_list();

/// An effect and its sizes, from `--effect NAME=SIZE[,SIZE...]` (sizes: a list "a,b,c" or a
/// grid "FROM:TO:STEP", cmdline/args.h number_grid).
struct EffectSizes {
  std::string effect;
  std::vector<double> sizes;
};

/// Parses NAME=SIZE[,SIZE...]. @throws std::invalid_argument naming the effect and its
/// parameter for an unknown effect, a size that is not a finite number or out of its range.
EffectSizes parse_effect_sizes(const std::string& text);

/// The overrides that make a scenario fly `effect` at `size`, given the scenario's resolved
/// tree (for the values whose ratios are kept). Size 0: enabled=false.
/// @throws std::invalid_argument naming the effect and parameter if the scenario gives nothing
///         to scale from (flapping_forcing without a first roll amplitude) or a scaled value
///         leaves its range.
std::vector<Override> size_overrides(const YAML::Node& scenario_tree, const std::string& effect, double size);

}  // namespace nimble::detection_power
