#include "effects/registry.h"

#include <algorithm>

#include "core/param_table.h"
#include "effects/actuator_delay.h"
#include "effects/constant_load.h"
#include "effects/dihedral_coupling.h"
#include "effects/effectiveness_drift.h"
#include "effects/effectiveness_step.h"
#include "effects/flapping_forcing.h"
#include "effects/forward_speed_coupling.h"
#include "effects/gravity_nonlinearity.h"
#include "effects/kinematic_coupling.h"
#include "effects/lateral_gust.h"
#include "effects/lateral_inflow.h"
#include "effects/sensor_bias.h"
#include "effects/yaw_coupling.h"

namespace nimble::effects {

const std::vector<Effect>& effect_registry() {
  static const std::vector<Effect> registry = {
      // The equations' form: terms the linear model leaves out, inputs and states it does not carry.
      kinematic_coupling_effect(),
      gravity_nonlinearity_effect(),
      lateral_inflow_effect(),
      forward_speed_coupling_effect(),
      actuator_delay_effect(),
      sensor_bias_effect(),
      constant_load_effect(),
      dihedral_coupling_effect(),
      yaw_coupling_effect(),
      // What changes over the flight or comes from a process.
      effectiveness_drift_effect(),
      effectiveness_step_effect(),
      flapping_forcing_effect(),
      lateral_gust_effect(),
  };
  return registry;
}

const Effect* find_effect(const std::string& name) {
  for (const auto& e : effect_registry()) {
    if (e.name() == name) return &e;
  }
  return nullptr;
}

const EffectDefinition* find_definition(const std::string& name) {
  const Effect* e = find_effect(name);
  return e ? &e->definition : nullptr;
}

std::string effect_name_list() {
  std::string list;
  for (const auto& e : effect_registry()) list += (list.empty() ? "" : ", ") + e.name();
  return list;
}

std::vector<const Effect*> plant_effects() {
  std::vector<const Effect*> out;
  for (const auto& e : effect_registry()) {
    if (e.has_plant_section()) out.push_back(&e);
  }
  return out;
}

std::vector<std::unique_ptr<EffectProcess>> make_effect_processes(const EffectsConfig& effects,
                                                                  ProcessContext& context) {
  std::vector<std::unique_ptr<EffectProcess>> out;
  for (const Effect* effect : plant_effects()) {
    if (auto process = effect->plant.make(effects, context)) out.push_back(std::move(process));
  }
  return out;
}

std::vector<Term> effect_terms(const EffectsConfig& effects, const Trim& trim) {
  std::vector<Term> out;
  for (const Effect* effect : plant_effects()) {
    if (!effect->plant.terms) continue;
    for (auto& t : effect->plant.terms(effects, trim)) out.push_back(std::move(t));
  }
  return out;
}

void effects_from(ConfigMap& section, EffectsConfig& effects) {
  for (const std::string& key : section.keys()) {
    const Effect* effect = find_effect(key);
    if (effect == nullptr || !effect->has_plant_section()) {
      std::string known;
      for (const Effect* e : plant_effects()) known += (known.empty() ? "" : ", ") + e->name();
      section.fail(key, "not an effect of the plant (known: " + known + ")");
    }
    ConfigMap m = section.get_map(key);
    effect->plant.load(m, effects);
    m.finish();
  }
  section.finish();
}

std::string effects_markdown() {
  std::string out = kParamsMarkdownHeader;
  for (const Effect* e : plant_effects()) out += e->plant.markdown_rows("plant.effects." + e->name() + ".");
  return out;
}

void check_model_effects(const DerivativeModel& model) {
  for (const auto& entry : model.effects) {
    if (find_effect(entry.first) != nullptr) continue;
    const ModelSection s{model, entry.first, entry.second};
    s.fail("unknown effect '" + entry.first + "' (known: " + effect_name_list() + ")");
  }
}

void apply_model_effects(const DerivativeModel& model, EffectsConfig& fx, std::map<std::string, double>& derivatives) {
  check_model_effects(model);
  for (const auto& entry : model.effects) {
    const ModelSection s{model, entry.first, entry.second};
    find_effect(entry.first)->from_model(s, fx, derivatives);
  }
}

}  // namespace nimble::effects
