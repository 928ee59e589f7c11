#include "plant/effects/registry.h"

#include <algorithm>

#include "core/effects.h"
#include "core/param_table.h"
#include "plant/effects/actuator_delay.h"
#include "plant/effects/constant_load.h"
#include "plant/effects/effectiveness_drift.h"
#include "plant/effects/effectiveness_step.h"
#include "plant/effects/flapping_forcing.h"
#include "plant/effects/forward_speed_coupling.h"
#include "plant/effects/lateral_gust.h"
#include "plant/effects/lateral_inflow.h"

namespace nimble::plant {
namespace {

/// Bounds of the derivatives a model's effects: section may set (wide sanity bounds: |L| terms
/// up to 0.1 N m per unit, |Y| terms up to 1 N per unit).
const Range kRollDerivative = Range::closed(-0.1, 0.1);
const Range kSideDerivative = Range::closed(-1.0, 1.0);

/// Sets derivative `name` from the section (a coefficient the section does not carry is left
/// as the model has it). Refuses one the model also carries among its derivatives: the two
/// would be two values of one term.
void set_derivative(const ModelSection& s, const std::string& name, std::map<std::string, double>& derivatives,
                    const Range& range) {
  const auto it = s.params.find(name);
  if (it == s.params.end()) return;
  if (s.model.derivatives.count(name)) {
    s.fail(name, "the model also carries " + name + " among its derivatives; give it in one place only");
  }
  s.in_range(name, it->second, range);
  derivatives[name] = it->second;
}

}  // namespace

const std::vector<PlantEffect>& plant_effects() {
  static const std::vector<PlantEffect> effects = {
      {"forward_speed_coupling",
       [](ConfigMap& m, EffectsConfig& e) { e.get<ForwardSpeedCouplingConfig>() = forward_speed_coupling_from(m); },
       [](const std::string& prefix) {
         return params_markdown_rows(forward_speed_coupling_params(), ForwardSpeedCouplingConfig{}, prefix);
       },
       "forward_speed_coupling",
       [](const ModelSection& s, EffectsConfig& e) {
         forward_speed_coupling_from_model(s, e.get<ForwardSpeedCouplingConfig>());
       },
       [](const EffectsConfig& e, ProcessContext&) {
         return forward_speed_coupling_process(e.get<ForwardSpeedCouplingConfig>());
       },
       [](const EffectsConfig& e) { return e.get<ForwardSpeedCouplingConfig>().enabled; },
       forward_speed_coupling_sizing},
      {"constant_load", [](ConfigMap& m, EffectsConfig& e) { e.get<ConstantLoadConfig>() = constant_load_from(m); },
       [](const std::string& prefix) {
         return params_markdown_rows(constant_load_params(), ConstantLoadConfig{}, prefix);
       },
       "constant_load",
       [](const ModelSection& s, EffectsConfig& e) { constant_load_from_model(s, e.get<ConstantLoadConfig>()); },
       [](const EffectsConfig& e, ProcessContext&) {
         return load_process<ConstantLoadConfig>(
             e.get<ConstantLoadConfig>(),
             [](const ConstantLoadConfig& c, const LoadInputs&, double& L, double& Y) { add_constant_load(c, L, Y); });
       },
       [](const EffectsConfig& e) { return e.get<ConstantLoadConfig>().enabled; }, constant_load_sizing},
      {"lateral_inflow", [](ConfigMap& m, EffectsConfig& e) { e.get<LateralInflowConfig>() = lateral_inflow_from(m); },
       [](const std::string& prefix) {
         return params_markdown_rows(lateral_inflow_params(), LateralInflowConfig{}, prefix);
       },
       "lateral_inflow",
       [](const ModelSection& s, EffectsConfig& e) { lateral_inflow_from_model(s, e.get<LateralInflowConfig>()); },
       [](const EffectsConfig& e, ProcessContext&) {
         return load_process<LateralInflowConfig>(e.get<LateralInflowConfig>(),
                                                  [](const LateralInflowConfig& c, const LoadInputs& in, double& L,
                                                     double& Y) { add_lateral_inflow(c, in.v_rel, L, Y); });
       },
       [](const EffectsConfig& e) { return e.get<LateralInflowConfig>().enabled; }, lateral_inflow_sizing},
      {"flapping_forcing",
       [](ConfigMap& m, EffectsConfig& e) { e.get<FlappingForcingConfig>() = flapping_forcing_from(m); },
       flapping_forcing_markdown_rows, "flapping_forcing",
       [](const ModelSection& s, EffectsConfig& e) { flapping_forcing_from_model(s, e.get<FlappingForcingConfig>()); },
       [](const EffectsConfig& e, ProcessContext& c) {
         return flapping_forcing_process(e.get<FlappingForcingConfig>(), c);
       },
       [](const EffectsConfig& e) { return e.get<FlappingForcingConfig>().enabled; }, flapping_forcing_sizing},
      {"actuator_delay", [](ConfigMap& m, EffectsConfig& e) { e.get<ActuatorDelayConfig>() = actuator_delay_from(m); },
       [](const std::string& prefix) {
         return params_markdown_rows(actuator_delay_params(), ActuatorDelayConfig{}, prefix);
       },
       "actuator_delay",
       [](const ModelSection& s, EffectsConfig& e) { actuator_delay_from_model(s, e.get<ActuatorDelayConfig>()); },
       [](const EffectsConfig& e, ProcessContext&) { return actuator_delay_process(e.get<ActuatorDelayConfig>()); },
       [](const EffectsConfig& e) { return e.get<ActuatorDelayConfig>().enabled; }, actuator_delay_sizing, true},
      {"lateral_gust", [](ConfigMap& m, EffectsConfig& e) { e.get<LateralGustConfig>() = lateral_gust_from(m); },
       [](const std::string& prefix) {
         return params_markdown_rows(lateral_gust_params(), LateralGustConfig{}, prefix) + "| `" + prefix +
                "form` | gauss_markov | gauss_markov, dryden | - | the gust's spectrum (lateral_gust.h) |\n";
       },
       "lateral_gust",
       [](const ModelSection& s, EffectsConfig& e) { lateral_gust_from_model(s, e.get<LateralGustConfig>()); },
       [](const EffectsConfig& e, ProcessContext& c) { return lateral_gust_process(e.get<LateralGustConfig>(), c); },
       [](const EffectsConfig& e) { return e.get<LateralGustConfig>().enabled; }, lateral_gust_sizing},
      {"effectiveness_drift",
       [](ConfigMap& m, EffectsConfig& e) { e.get<EffectivenessDriftConfig>() = effectiveness_drift_from(m); },
       [](const std::string& prefix) {
         return params_markdown_rows(effectiveness_drift_params(), EffectivenessDriftConfig{}, prefix);
       },
       "effectiveness_drift",
       [](const ModelSection& s, EffectsConfig& e) {
         effectiveness_drift_from_model(s, e.get<EffectivenessDriftConfig>());
       },
       [](const EffectsConfig& e, ProcessContext&) {
         return load_process<EffectivenessDriftConfig>(
             e.get<EffectivenessDriftConfig>(),
             [](const EffectivenessDriftConfig& c, const LoadInputs& in, double& L, double& Y) {
               add_effectiveness_drift(c, in.t_s, in.roll_input_nm, in.roll_input_n, L, Y);
             });
       },
       [](const EffectsConfig& e) { return e.get<EffectivenessDriftConfig>().enabled; }, nullptr},
      {"effectiveness_step",
       [](ConfigMap& m, EffectsConfig& e) { e.get<EffectivenessStepConfig>() = effectiveness_step_from(m); },
       [](const std::string& prefix) {
         return params_markdown_rows(effectiveness_step_params(), EffectivenessStepConfig{}, prefix);
       },
       "effectiveness_step",
       [](const ModelSection& s, EffectsConfig& e) {
         effectiveness_step_from_model(s, e.get<EffectivenessStepConfig>());
       },
       [](const EffectsConfig& e, ProcessContext&) {
         return load_process<EffectivenessStepConfig>(
             e.get<EffectivenessStepConfig>(),
             [](const EffectivenessStepConfig& c, const LoadInputs& in, double& L, double& Y) {
               add_effectiveness_step(c, in.t_s, in.roll_input_nm, in.roll_input_n, L, Y);
             });
       },
       [](const EffectsConfig& e) { return e.get<EffectivenessStepConfig>().enabled; }, nullptr},
  };
  return effects;
}

std::vector<std::unique_ptr<EffectProcess>> make_effect_processes(const EffectsConfig& effects,
                                                                  ProcessContext& context) {
  std::vector<std::unique_ptr<EffectProcess>> out;
  for (const PlantEffect& effect : plant_effects()) {
    if (auto process = effect.make(effects, context)) out.push_back(std::move(process));
  }
  return out;
}

void effects_from(ConfigMap& section, EffectsConfig& effects) {
  for (const std::string& key : section.keys()) {
    const auto& all = plant_effects();
    const auto it = std::find_if(all.begin(), all.end(), [&](const PlantEffect& e) { return e.name == key; });
    if (it == all.end()) {
      std::string known;
      for (const auto& e : all) known += (known.empty() ? "" : ", ") + e.name;
      section.fail(key, "not an effect of the plant (known: " + known + ")");
    }
    ConfigMap m = section.get_map(key);
    it->load(m, effects);
    m.finish();
  }
  section.finish();
}

std::string effects_markdown() {
  std::string out = kParamsMarkdownHeader;
  for (const auto& e : plant_effects()) out += e.markdown_rows("plant.effects." + e.name + ".");
  return out;
}

const std::vector<std::string>& effects_in_equations_of_motion() {
  static const std::vector<std::string> names{"kinematic_coupling", "gravity_nonlinearity"};
  return names;
}

void apply_model_effects(const DerivativeModel& model, EffectsConfig& fx, std::map<std::string, double>& derivatives) {
  const auto& eom = effects_in_equations_of_motion();
  for (const auto& entry : model.effects) {
    const std::string& name = entry.first;  // a lambda cannot capture a structured binding in C++17
    const ModelSection s{model, name, entry.second};
    const auto& all = plant_effects();
    const auto plant_effect =
        std::find_if(all.begin(), all.end(), [&](const PlantEffect& e) { return e.model_effect == name; });
    if (plant_effect != all.end()) {
      plant_effect->from_model(s, fx);
    } else if (name == "sensor_bias") {
      // The discrepancy library's sensor_bias fits the same constant L_0 and Y_0 as constant_load
      // (they differ in what the rate gyro shows against the kinematics): the plant flies it as
      // that constant load, the same moment and force (a bias of the simulated IMU is
      // sensing.imu's, not the model's).
      constant_load_from_model(s, fx.get<ConstantLoadConfig>());
    } else if (name == "dihedral_coupling") {
      // Regressor delta_d in L and Y: the dihedral derivatives.
      s.check_keys({"L_dd", "Y_dd"});
      set_derivative(s, "L_dd", derivatives, kRollDerivative);
      set_derivative(s, "Y_dd", derivatives, kSideDerivative);
    } else if (name == "yaw_coupling") {
      // Regressor r in L and Y: the yaw-rate derivatives. They act only where r is a state (a
      // lateral4 model); with a lateral3 model the plant holds r at trim (0), as the vehicle's
      // yaw loop would, and they are inert.
      s.check_keys({"Lr", "Yr"});
      set_derivative(s, "Lr", derivatives, kRollDerivative);
      set_derivative(s, "Yr", derivatives, kSideDerivative);
    } else if (std::find(eom.begin(), eom.end(), name) != eom.end()) {
      // Nothing to add: Y_pw is the coefficient of p (w - w0), the part of the kinematic term
      // p w of v_dot that Eq 21 linearises at w0, and Y_gphi that of g (sin phi - phi)
      // cos theta0; the plant's equations of motion (Eq 3.1) carry p w and
      // g cos(theta) sin(phi) exactly, with the vehicle's mass.
      s.check_keys({name == "kinematic_coupling" ? "Y_pw" : "Y_gphi"});
    } else {
      s.fail("effect '" + name + "' is not one the plant can fly (known: " + effect_name_list() + ")");
    }
  }
}

}  // namespace nimble::plant
