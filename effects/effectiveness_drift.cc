#include "effects/effectiveness_drift.h"

#include <cmath>

namespace nimble::effects {

const ParamTable<EffectivenessDriftConfig>& effectiveness_drift_params() {
  using C = EffectivenessDriftConfig;
  static const ParamTable<C> table = {
      {"enabled", &C::enabled, Range::any(), "-", "fly the effect (required)"},
      {"rate_per_min", &C::rate_per_min, Range::closed(-0.5, 0.5), "1/min",
       "L_df and Y_df scale with 1 + rate (t - t_ref) / 60 (battery sag: negative; clamped at 0)"},
      {"t_ref_s", &C::t_ref_s, Range::closed(0.0, 3600.0), "s", "time at which the scale is 1"},
  };
  return table;
}

EffectivenessDriftConfig effectiveness_drift_from(ConfigMap& map) {
  EffectivenessDriftConfig c;
  c.enabled = map.get_bool("enabled");
  read_params(map, effectiveness_drift_params(), c);
  return c;
}

void effectiveness_drift_from_model(const ModelSection& s, EffectivenessDriftConfig& c) {
  // Regressor (t - t_mid) delta_f in L and Y: L_df_rate = L_df rate / 60 s/min with L_df the
  // model's value at t_mid.
  s.check_keys({"L_df_rate", "Y_df_rate", "rate_per_min", "rate_per_min_lo", "rate_per_min_hi", "t_mid_s"});
  c.enabled = true;
  const auto& rate_range = range_of(effectiveness_drift_params(), "rate_per_min");
  double rate = 0.0;
  bool found = false;
  for (const char* eq : {"L", "Y"}) {
    const std::string key = std::string(eq) + "_df_rate", input = std::string(eq) + "_df";
    const auto it = s.params.find(key);
    if (found || it == s.params.end()) continue;
    const auto d = s.model.derivatives.find(input);
    if (d == s.model.derivatives.end() || d->second == 0.0) s.fail(key, "needs the model's " + input + " (not 0)");
    rate = 60.0 * it->second / d->second;
    s.in_range(key + " / " + input + " per minute", rate, rate_range);
    found = true;
  }
  if (!found) rate = s.required("rate_per_min", rate_range);
  c.rate_per_min = rate;
  c.t_ref_s = s.or_zero("t_mid_s", range_of(effectiveness_drift_params(), "t_ref_s"));
}

Effect effectiveness_drift_effect() {
  Effect e;
  e.definition = {"effectiveness_drift",
                  "(t - t_mid) delta_f in roll moment and side force: the flap input's effectiveness drifts over the "
                  "flight (battery sag), named with its rate as a fraction of L_df per minute",
                  {},
                  {{"L", "L_df_rate", "(t - t_mid) delta_f", ColumnForm::kInputTimesTime},
                   {"Y", "Y_df_rate", "(t - t_mid) delta_f", ColumnForm::kInputTimesTime}},
                  Scan::kNone,
                  Signature::kNone,
                  EffectivenessChange::kDrift,
                  "plant.effects.effectiveness_drift: L_df, Y_df x (1 + rate_per_min (t - t_ref) / 60)"};
  e.from_model = config_from_model(effectiveness_drift_from_model);
  e.plant = table_plant_side(effectiveness_drift_from, effectiveness_drift_params);
  e.plant.make = [](const EffectsConfig& fx, ProcessContext&) {
    return load_process<EffectivenessDriftConfig>(
        fx.get<EffectivenessDriftConfig>(),
        [](const EffectivenessDriftConfig& c, const LoadInputs& in, double& L, double& Y) {
          add_effectiveness_drift(c, in.t_s, in.roll_input_nm, in.roll_input_n, L, Y);
        });
  };
  return e;
}

}  // namespace nimble::effects
