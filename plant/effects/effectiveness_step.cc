#include "plant/effects/effectiveness_step.h"

namespace nimble::plant {

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

}  // namespace nimble::plant
