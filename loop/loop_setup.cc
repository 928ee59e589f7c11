#include "loop/loop_setup.h"

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "controller/manoeuvre.h"
#include "core/input_file.h"
#include "effects/actuator_delay.h"
#include "effects/registry.h"
#include "plant/plant_model.h"

namespace nimble::loop {

RollLoopConfig LoopSetup::loop_config(const GainSet& gains) const {
  RollLoopConfig c = roll_loop_config(controller, gains);
  c.flap_gain_per_s = flap_gain_per_s;
  c.flap_pole_radps = flap_pole_radps;
  c.latency_s = latency_s();
  return c;
}

double pipeline_latency_s(const std::string& input, const std::string& clock, const std::string& trigger,
                          double control_rate_hz) {
  if (clock == "realtime") return trigger == "state" ? 0.0 : 1.0 / control_rate_hz;
  return input == "estimate" ? 2.0 / control_rate_hz : 0.0;
}

LoopSetup loop_setup(const std::string& file, const std::vector<Override>& overrides, const std::string& model_file,
                     const std::string& input, const std::string& clock) {
  const Scenario scenario = load_scenario(file, overrides);
  LoopSetup s;
  s.scenario_file = file;
  ConfigMap plant_section = scenario.section("plant");
  const plant::PlantConfig plant = plant::plant_config_from(plant_section);
  s.flap_gain_per_s = plant.flap.delta_f_gain_radps;
  s.flap_pole_radps = plant.flap.pole_radps;
  s.plant_rate_hz = plant.rate_hz;
  const auto& fx = plant.effects;
  if (fx.get<effects::ActuatorDelayConfig>().enabled && fx.get<effects::ActuatorDelayConfig>().delay_s > 0.0) {
    // The plant applies the newest command issued at least delay_s before each of its steps.
    s.actuator_delay_s =
        std::ceil(fx.get<effects::ActuatorDelayConfig>().delay_s * plant.rate_hz - 1e-6) / plant.rate_hz;
  }
  // Every enabled plant effect the linear loop leaves out, from the registry.
  for (const effects::Effect* e : effects::plant_effects()) {
    if (!e->plant.in_linear_loop && e->plant.enabled(fx)) s.nonlinear_effects.push_back(e->name());
  }

  s.model = load_model(model_file.empty() ? scenario.model_file : model_file);
  s.vehicle =
      load_vehicle(scenario.vehicle_file.empty() || !model_file.empty() ? s.model.vehicle_file : scenario.vehicle_file);
  if (!s.model.effects.empty()) s.nonlinear_effects.push_back("the model's effects: section");
  ConfigMap controller_section = scenario.section("controller");
  s.controller = controller_config_from(controller_section);
  s.gain_set = s.controller.default_gain_set;
  if (const std::string file = manoeuvre_file(scenario); !file.empty()) s.gain_set = load_manoeuvre(file).gain_set;
  const ProcessRunOptions run = process_run_options(scenario);
  s.input = input.empty() ? run.controller_input : input;
  if (s.input != "truth" && s.input != "estimate") {
    throw std::invalid_argument("the controller's input must be truth or estimate, got '" + s.input + "'");
  }
  s.clock = clock.empty() ? scenario.clock : clock;
  if (s.clock != "realtime" && s.clock != "lockstep" && s.clock != "inprocess") {
    throw std::invalid_argument("the clock must be realtime, lockstep or inprocess, got '" + s.clock + "'");
  }
  s.trigger = run.controller_trigger;
  s.pipeline_latency_s = pipeline_latency_s(s.input, s.clock, s.trigger, s.controller.rate_hz);
  return s;
}

const std::vector<std::string>& loop_derivatives() {
  static const std::vector<std::string> names{"Lp", "Lv", "L_df", "Yp", "Yv", "Y_df"};
  return names;
}

DerivativeBox derivative_box(const std::string& file) {
  DerivativeBox box;
  box.source = file;
  const bool json = file.size() > 5 && file.substr(file.size() - 5) == ".json";
  if (!json) {
    const DerivativeModel m = load_model(file);
    DerivativeBox b = derivative_box(m);
    b.source = file;
    return b;
  }
  std::string text;
  try {
    text = read_input_file(file, InputKind::kConfig);  // a regular file within a configuration file's bound
  } catch (const InputFileError& e) {
    throw std::invalid_argument(std::string("derivative box: ") + e.what());
  }
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const std::exception& e) {
    throw std::invalid_argument("derivative box: " + file + " is not JSON: " + e.what());
  }
  if (!j.contains("parameters") || !j["parameters"].is_object()) {
    throw std::invalid_argument("derivative box: " + file + " has no 'parameters' (a rig identify --json report)");
  }
  for (const std::string& name : loop_derivatives()) {
    const auto& p = j["parameters"];
    if (!p.contains(name) || !p[name].contains("value") || !p[name].contains("sigma") ||
        !p[name]["value"].is_number() || !p[name]["sigma"].is_number()) {
      throw std::invalid_argument("derivative box: " + file + " has no value and sigma of " + name);
    }
    box.value[name] = p[name]["value"].get<double>();
    box.sigma[name] = p[name]["sigma"].get<double>();
  }
  return box;
}

DerivativeBox derivative_box(const DerivativeModel& model) {
  DerivativeBox box;
  box.source = model.file;
  for (const std::string& name : loop_derivatives()) {
    const auto s = model.published_sigma.find(name);
    if (s == model.published_sigma.end()) {
      throw std::invalid_argument("derivative box: model " + model.name + " has no published sigma of " + name);
    }
    box.value[name] = model.at(name);
    box.sigma[name] = s->second;
  }
  return box;
}

DerivativeModel box_point(const DerivativeModel& model, const DerivativeBox& box, const std::vector<int>& signs,
                          double k) {
  DerivativeModel m = model;
  const auto& names = loop_derivatives();
  for (std::size_t i = 0; i < names.size(); ++i) {
    const int sign = i < signs.size() ? signs[i] : 0;
    m.derivatives[names[i]] = box.value.at(names[i]) + sign * k * box.sigma.at(names[i]);
  }
  return m;
}

}  // namespace nimble::loop
