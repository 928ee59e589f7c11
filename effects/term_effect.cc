#include "effects/term_effect.h"

#include <stdexcept>
#include <utility>

#include "core/param_table.h"
#include "core/term_expression.h"

namespace nimble::effects {
namespace {

/// The plant's terms of `definition` with the coefficients `values` (a column the section does
/// not carry adds nothing), `trim`'s u0 and w0 put in: the plant's u and w are the whole
/// velocities, trim included.
std::vector<Term> plant_terms(const EffectDefinition& definition, const std::map<std::string, double>& values,
                              const Trim& trim) {
  std::vector<Term> out;
  for (const EffectColumn& c : definition.terms) {
    const auto it = values.find(c.parameter);
    if (it == values.end() || it->second == 0.0) continue;
    out.push_back({c.equation, TermExpression::parse(column_term(c, trim.u0_mps, trim.w0_mps)), it->second,
                   "plant.effects." + definition.name + "." + c.parameter});
  }
  return out;
}

std::string markdown_rows(const EffectDefinition& definition, const std::string& prefix) {
  std::string out = "| `" + prefix + "enabled` | false | true, false | - | fly the effect (required) |\n";
  for (const EffectColumn& c : definition.terms) {
    out += "| `" + prefix + c.parameter + "` | 0 | " + c.range.describe() + " | " + c.unit + " | " + c.equation +
           " += " + c.parameter + " " + c.regressor + " |\n";
  }
  return out;
}

}  // namespace

Effect term_effect(EffectDefinition definition) {
  for (const EffectColumn& c : definition.terms) {
    if (c.form != ColumnForm::kTerm || c.equation == "F") {
      throw std::logic_error("effect " + definition.name + ": column " + c.parameter + " is not a load term");
    }
    TermExpression::parse(column_term(c, 0.0, 0.0));  // parses whatever the trim
  }
  const std::string name = definition.name;
  Effect e;
  e.definition = std::move(definition);
  const EffectDefinition def = e.definition;
  e.from_model = [def](const ModelSection& s, EffectsConfig& fx, std::map<std::string, double>&) {
    std::vector<std::string> keys;
    for (const EffectColumn& c : def.terms) keys.push_back(c.parameter);
    s.check_keys(keys);
    auto& values = fx.get<TermEffectsConfig>().on[def.name];
    values.clear();
    for (const EffectColumn& c : def.terms) values[c.parameter] = s.or_zero(c.parameter, c.range);
  };
  e.plant.load = [def](ConfigMap& m, EffectsConfig& fx) {
    auto& on = fx.get<TermEffectsConfig>().on;
    on.erase(def.name);
    const bool enabled = m.get_bool("enabled");
    std::map<std::string, double> values;
    for (const EffectColumn& c : def.terms) values[c.parameter] = m.get_double_or(c.parameter, 0.0, c.range);
    if (enabled) on[def.name] = values;
  };
  e.plant.markdown_rows = [def](const std::string& prefix) { return markdown_rows(def, prefix); };
  e.plant.make = [](const EffectsConfig&, ProcessContext&) { return std::unique_ptr<EffectProcess>(); };
  e.plant.enabled = [name](const EffectsConfig& fx) { return fx.get<TermEffectsConfig>().on.count(name) > 0; };
  e.plant.terms = [def](const EffectsConfig& fx, const Trim& trim) {
    const auto& on = fx.get<TermEffectsConfig>().on;
    const auto it = on.find(def.name);
    return it == on.end() ? std::vector<Term>{} : plant_terms(def, it->second, trim);
  };
  return e;
}

}  // namespace nimble::effects
