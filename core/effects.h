#pragma once
/// The effects the rig knows beyond the linear derivatives, named once: the registry that a
/// model file's `effects:` section (core/model.h), the plant (plant/effects/), the discrepancy
/// workflow's candidate library (discrepancy/discrepancy.h) and the command-line help all read.
///
/// Each entry is an effect as the identification sees it: its physics, the data it needs, the
/// regressor columns it adds to the roll-moment (L), side-force (Y) and flap-actuator (F)
/// equations, whose coefficients are the parameters a model's `effects:` section carries, and
/// how the plant flies it. Adding an effect: plant/effects/README.md.

#include <string>
#include <vector>

namespace nimble {

/// One regressor column of an effect in one equation.
struct EffectTerm {
  std::string equation;   ///< "L", "Y" or "F"
  std::string parameter;  ///< the coefficient's name in a model's effects: section, e.g. "Y_vv"
  std::string regressor;  ///< documented form, e.g. "v|v|"
};

/// One effect of the registry.
struct EffectSpec {
  std::string name;                ///< e.g. "lateral_inflow" (the plant's effect name where it has one)
  std::string physics;             ///< one line
  std::vector<std::string> needs;  ///< data channels it needs besides p, v, phi, delta_f
  std::vector<EffectTerm> terms;   ///< its regressor columns (none for a stochastic effect)
  bool scanned = false;            ///< has a scanned parameter (a delay, a frequency)
  bool wideband = false;           ///< tested on data low-passed above the flapping band
  bool stochastic = false;         ///< no regressor: named from its signature in the residual
  std::string plant;               ///< how the plant flies it (plant/effects/)
};

/// Every effect, in a fixed order.
const std::vector<EffectSpec>& effect_registry();

/// The effect called `name`, or nullptr.
const EffectSpec* find_effect(const std::string& name);

/// The effects' names, in the registry's order, joined by ", " (help texts, error messages).
std::string effect_name_list();

}  // namespace nimble
