#include "effects/actuator_delay.h"

#include <string>

namespace nimble::effects {
namespace {

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() > suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

const ParamTable<ActuatorDelayConfig>& actuator_delay_params() {
  using C = ActuatorDelayConfig;
  static const ParamTable<C> table = {
      {"enabled", &C::enabled, Range::any(), "-", "fly the effect (required)"},
      {"delay_s", &C::delay_s, Range::closed(0.0, 0.5), "s", "pure delay of every actuator command"},
  };
  return table;
}

ActuatorDelayConfig actuator_delay_from(ConfigMap& map) {
  ActuatorDelayConfig c;
  c.enabled = map.get_bool("enabled");
  read_params(map, actuator_delay_params(), c);
  return c;
}

void actuator_delay_from_model(const ModelSection& s, ActuatorDelayConfig& c) {
  // The workflow finds that delta_f acts delay_s later than recorded (regressor
  // delta_f(t - tau) - delta_f(t)). The plant delays every command (the servos too) and all of
  // the input (the workflow names the effect only when most of it acts delayed); the
  // regression's coefficients of the delayed column, the delayed fractions and an
  // actuator-equation coefficient are accepted but not needed.
  s.check_keys(
      [](const std::string& k) {
        return k == "delay_s" || ends_with(k, "_df_delayed") || ends_with(k, "_df_fraction_delayed") ||
               ends_with(k, "_cmd_delayed");
      },
      "delay_s, <eq>_df_delayed, <eq>_df_fraction_delayed, <eq>_cmd_delayed");
  c.enabled = true;
  c.delay_s = s.required("delay_s", range_of(actuator_delay_params(), "delay_s"));
}

namespace {

class ActuatorDelayProcess : public EffectProcess {
 public:
  explicit ActuatorDelayProcess(const ActuatorDelayConfig& config) : config_(config) {}
  ActuatorInput command(double t_s, const ActuatorInput& issued, const ActuatorInput& trim) override {
    return delay_.apply(config_, t_s, issued, trim);
  }

 private:
  ActuatorDelayConfig config_;
  CommandDelay<ActuatorInput> delay_;
};

}  // namespace

std::unique_ptr<EffectProcess> actuator_delay_process(const ActuatorDelayConfig& config) {
  if (!config.enabled || config.delay_s <= 0.0) return nullptr;
  return std::make_unique<ActuatorDelayProcess>(config);
}

EffectSizing actuator_delay_sizing() {
  return {"delay_s", "s", range_of(actuator_delay_params(), "delay_s"), "nothing else",
          [](const YAML::Node&, double size) { return parameter_alone("delay_s", size); }};
}

Effect actuator_delay_effect() {
  Effect e;
  e.definition = {"actuator_delay",
                  "delta_f(t - tau) - delta_f(t): the flap input acts tau later than recorded, tau scanned over 1 "
                  "sample .. delay_max_s",
                  {},
                  {{"L", "L_df_delayed", "delta_f(t - tau) - delta_f(t)", ColumnForm::kDelayedInput},
                   {"Y", "Y_df_delayed", "delta_f(t - tau) - delta_f(t)", ColumnForm::kDelayedInput},
                   {"F", "F_cmd_delayed", "delta_f_cmd(t - t0 - tau) - delta_f_cmd(t - t0), t0 the command latency",
                    ColumnForm::kDelayedInput}},
                  Scan::kDelay,
                  Signature::kNone,
                  EffectivenessChange::kNone,
                  "plant.effects.actuator_delay: pure command delay of delay_s"};
  e.from_model = config_from_model(actuator_delay_from_model);
  e.plant = table_plant_side(actuator_delay_from, actuator_delay_params);
  e.plant.make = [](const EffectsConfig& fx, ProcessContext&) {
    return actuator_delay_process(fx.get<ActuatorDelayConfig>());
  };
  e.plant.sizing = actuator_delay_sizing;
  e.plant.in_linear_loop = true;
  return e;
}

}  // namespace nimble::effects
