#include "effects/effectiveness_step.h"

namespace nimble::effects {

const ParamTable<EffectivenessStepConfig>& effectiveness_step_params() {
  using C = EffectivenessStepConfig;
  static const ParamTable<C> table = {
      {"enabled", &C::enabled, Range::any(), "-", "fly the effect (required)"},
      {"t_change_s", &C::t_change_s, Range::closed(0.0, 3600.0), "s", "time of the change"},
      {"roll_fraction", &C::roll_fraction, Range::closed(-1.0, 1.0), "-",
       "L_df changes by this fraction from t_change_s on (a damaged wing: negative)"},
      {"side_fraction", &C::side_fraction, Range::closed(-1.0, 1.0), "-",
       "Y_df changes by this fraction from t_change_s on"},
  };
  return table;
}

EffectivenessStepConfig effectiveness_step_from(ConfigMap& map) {
  EffectivenessStepConfig c;
  c.enabled = map.get_bool("enabled");
  read_params(map, effectiveness_step_params(), c);
  return c;
}

void effectiveness_step_from_model(const ModelSection& s, EffectivenessStepConfig& c) {
  // Regressor H(t - t_change) delta_f in L and Y: L_df_step = L_df roll_fraction with L_df the
  // model's value before the change.
  s.check_keys({"L_df_step", "Y_df_step", "t_change_s", "t_change_lo_s", "t_change_hi_s", "fraction", "fraction_lo",
                "fraction_hi"});
  c.enabled = true;
  c.t_change_s = s.required("t_change_s", range_of(effectiveness_step_params(), "t_change_s"));
  auto fraction = [&](const std::string& key, const std::string& input, const char* param) {
    const auto it = s.params.find(key);
    if (it == s.params.end()) return 0.0;
    const auto d = s.model.derivatives.find(input);
    if (d == s.model.derivatives.end() || d->second == 0.0) s.fail(key, "needs the model's " + input + " (not 0)");
    const double f = it->second / d->second;
    s.in_range(key + " / " + input, f, range_of(effectiveness_step_params(), param));
    return f;
  };
  c.roll_fraction = fraction("L_df_step", "L_df", "roll_fraction");
  c.side_fraction = fraction("Y_df_step", "Y_df", "side_fraction");
}

Effect effectiveness_step_effect() {
  Effect e;
  e.definition = {"effectiveness_step",
                  "H(t - t*) delta_f in roll moment and side force: the flap input's effectiveness changes at an "
                  "unknown time t* (a damaged wing), t* scanned over the record away from its ends, named with "
                  "t_change_s and the fractional change",
                  {},
                  {{"L", "L_df_step", "H(t - t*) delta_f", ColumnForm::kInputAfterChange},
                   {"Y", "Y_df_step", "H(t - t*) delta_f", ColumnForm::kInputAfterChange}},
                  Scan::kChangeTime,
                  Signature::kNone,
                  EffectivenessChange::kStep,
                  "plant.effects.effectiveness_step: L_df x (1 + roll_fraction), Y_df x (1 + side_fraction) from "
                  "t_change_s on"};
  e.from_model = config_from_model(effectiveness_step_from_model);
  e.plant = table_plant_side(effectiveness_step_from, effectiveness_step_params);
  e.plant.make = [](const EffectsConfig& fx, ProcessContext&) {
    return load_process<EffectivenessStepConfig>(
        fx.get<EffectivenessStepConfig>(),
        [](const EffectivenessStepConfig& c, const LoadInputs& in, double& L, double& Y) {
          add_effectiveness_step(c, in.t_s, in.roll_input_nm, in.roll_input_n, L, Y);
        });
  };
  return e;
}

}  // namespace nimble::effects
