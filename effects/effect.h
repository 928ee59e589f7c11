#pragma once
/// One effect beyond the paper's linear model, defined once for every part of the rig that
/// knows it: its name and physics, the regressor columns it adds to the roll-moment (L),
/// side-force (Y) and flap-actuator (F) equations (as terms of core/term_expression.h where
/// the grammar can state them), the roles the discrepancy workflow gives it, and how the plant
/// flies it (its `plant.effects.<name>` section, its mapping from a model's `effects:` section,
/// its process). Each effect is one file pair of this folder that returns its `Effect`; the
/// registry (registry.h) lists them. Adding an effect: README.md here.

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/config.h"
#include "core/param_table.h"
#include "core/terms.h"
#include "effects/effect_process.h"
#include "effects/effect_sizing.h"
#include "effects/effects_config.h"
#include "effects/model_section.h"

namespace nimble::effects {

/// How a regressor column is computed from the flight data.
enum class ColumnForm {
  kTerm,              ///< EffectColumn::term in the term grammar, the trim's values put for u0 and w0
  kGravityResidual,   ///< g (sin phi - phi) cos theta0: the part of gravity Eq 21 linearises
  kDelayedInput,      ///< delta_f(t - tau) - delta_f(t), tau the scanned delay (in F: the applied command's)
  kInputTimesTime,    ///< (t - t_mid) delta_f, t_mid the record's middle
  kInputAfterChange,  ///< H(t - t*) delta_f, t* the scanned change time
  kHarmonic,          ///< sin or cos of h 2 pi f t, f the scanned flapping frequency
};

/// One regressor column of an effect in one equation.
struct EffectColumn {
  EffectColumn(std::string equation_, std::string parameter_, std::string regressor_, ColumnForm form_,
               std::string term_ = "", std::string unit_ = "", Range range_ = Range::any())
      : equation(std::move(equation_)),
        parameter(std::move(parameter_)),
        regressor(std::move(regressor_)),
        form(form_),
        term(std::move(term_)),
        unit(std::move(unit_)),
        range(range_) {}

  std::string equation;   ///< "L", "Y" or "F"
  std::string parameter;  ///< the coefficient's name in a model's effects: section, e.g. "Y_vv"
  std::string regressor;  ///< documented form, e.g. "v|v|"
  ColumnForm form;
  std::string term;  ///< kTerm: the column in the term grammar, e.g. "v*abs(v)"; u0, w0 stand for the trim
  /// The coefficient's unit and range (a term effect's plant section reads it with them).
  std::string unit;
  Range range;
};

/// What the effect's scanned parameter is (the workflow scans it over a grid).
enum class Scan {
  kNone,
  kDelay,          ///< a delay of the flap input, 1 sample .. delay_max_s; named as delay_s
  kChangeTime,     ///< the time of a change, over the record away from its ends; named as t_change_s
  kFrequency,      ///< the flapping frequency, on data low-passed above the flapping band
  kFormParameter,  ///< a generic form's parameter (a width, a time constant) over its family's grid
};

/// How the workflow tells a significant effect from its rivals.
enum class Signature {
  kNone,
  kInflow,            ///< a function of v: tested against the side gust's signature in the residual
  kRateGyroBias,      ///< a constant that the rate gyro carries (p against phi's derivative disagree)
  kConstantLoad,      ///< a constant the kinematics agree with (p agrees with phi's derivative)
  kResidualSpectrum,  ///< stochastic, no regressor: named from its signature in the residual spectrum
};

/// How the flap input's effectiveness changes over the record, for the effects that change it.
enum class EffectivenessChange { kNone, kDrift, kStep };

/// The effect as the identification and the discrepancy workflow see it.
struct EffectDefinition {
  std::string name;                 ///< e.g. "lateral_inflow"
  std::string physics;              ///< one line
  std::vector<std::string> needs;   ///< data channels it needs besides p, v, phi, delta_f
  std::vector<EffectColumn> terms;  ///< its regressor columns (none for a stochastic effect)
  Scan scan = Scan::kNone;
  Signature signature = Signature::kNone;
  EffectivenessChange change = EffectivenessChange::kNone;
  std::string plant;  ///< how the plant flies it (help texts)

  bool scanned() const { return scan != Scan::kNone; }
  /// Tested on data low-passed above the flapping band.
  bool wideband() const { return scan == Scan::kFrequency; }
  /// No regressor: named from its signature in the residual.
  bool stochastic() const { return signature == Signature::kResidualSpectrum; }
  /// Its columns are constants: exempt from the excitation floor and from the test above the
  /// gust band, where a constant has no content.
  bool constant() const { return signature == Signature::kRateGyroBias || signature == Signature::kConstantLoad; }
  /// The model parameter its scan names ("delay_s", "t_change_s"), or "".
  std::string scan_parameter() const;
};

/// The plant's side of an effect with a `plant.effects.<name>` section (PlantModel flies it).
struct PlantSide {
  /// Reads its section into `effects`. @throws ConfigError naming the key.
  std::function<void(ConfigMap& section, EffectsConfig& effects)> load;
  /// Its parameters as Markdown rows (key, default, allowed, unit, meaning), keys after `prefix`.
  std::function<std::string(const std::string& prefix)> markdown_rows;
  /// Its process while the plant flies (effect_process.h), or none when it does nothing in
  /// `effects`. @throws std::invalid_argument for a configuration the effect cannot fly.
  std::function<std::unique_ptr<EffectProcess>(const EffectsConfig& effects, ProcessContext& context)> make;
  /// True if the effect is on in `effects` (what `rig loop` names as left out of its linear loop).
  std::function<bool(const EffectsConfig& effects)> enabled;
  /// The terms it adds to the plant's loads (a term effect's), none for the others; `trim` is the
  /// plant's trim, put for u0 and w0 (the plant's u and w are the whole velocities).
  std::function<std::vector<Term>(const EffectsConfig& effects, const Trim& trim)> terms;
  /// What one number SIZE sets (effect_sizing.h: `rig discrepancy --power`), or nullptr.
  EffectSizing (*sizing)() = nullptr;
  /// True if its process acts only on the commands, which the linear loop of `rig loop` models
  /// as a delay (so `rig loop` does not name it as left out).
  bool in_linear_loop = false;
};

/// One effect: its definition, how a model's `effects:` section makes the plant fly it, and its
/// plant section where it has one.
struct Effect {
  EffectDefinition definition;
  /// Makes `effects` (the plant file's effects) and `derivatives` (the model's derivatives, as
  /// the plant will fly them) fly the section. @throws std::invalid_argument naming the model,
  /// the effect and the parameter.
  std::function<void(const ModelSection& section, EffectsConfig& effects, std::map<std::string, double>& derivatives)>
      from_model;
  /// Empty `load` for an effect without a plant section of its own.
  PlantSide plant;

  const std::string& name() const { return definition.name; }
  bool has_plant_section() const { return static_cast<bool>(plant.load); }
};

/// The mapping from a model's section of an effect whose plant configuration is `Config`:
/// `from_model` sets that configuration from the section.
template <class Config>
auto config_from_model(void (*from_model)(const ModelSection&, Config&)) {
  return [from_model](const ModelSection& s, EffectsConfig& fx, std::map<std::string, double>&) {
    from_model(s, fx.get<Config>());
  };
}

/// The plant side of an effect whose configuration `Config` is read by `from` and described by
/// `params` (its rows in `rig params`), on when `Config::enabled`; the effect adds its process and
/// its sizing.
template <class Config>
PlantSide table_plant_side(Config (*from)(ConfigMap&), const ParamTable<Config>& (*params)()) {
  PlantSide p;
  p.load = [from](ConfigMap& m, EffectsConfig& fx) { fx.get<Config>() = from(m); };
  p.markdown_rows = [params](const std::string& prefix) { return params_markdown_rows(params(), Config{}, prefix); };
  p.enabled = [](const EffectsConfig& fx) { return fx.get<Config>().enabled; };
  return p;
}

/// The column of `c` (kTerm) with the trim's values put for u0 and w0, in the term grammar.
std::string column_term(const EffectColumn& c, double u0_mps, double w0_mps);

}  // namespace nimble::effects
