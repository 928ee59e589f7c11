#include "effects/constant_load.h"

namespace nimble::effects {

const ParamTable<ConstantLoadConfig>& constant_load_params() {
  using C = ConstantLoadConfig;
  static const ParamTable<C> table = {
      {"enabled", &C::enabled, Range::any(), "-", "fly the effect (required)"},
      {"L_0", &C::roll_moment_nm, Range::closed(-0.1, 0.1), "N m", "constant roll moment"},
      {"Y_0", &C::side_force_n, Range::closed(-1.0, 1.0), "N", "constant side force"},
  };
  return table;
}

ConstantLoadConfig constant_load_from(ConfigMap& map) {
  ConstantLoadConfig c;
  c.enabled = map.get_bool("enabled");
  read_params(map, constant_load_params(), c);
  return c;
}

void constant_load_from_model(const ModelSection& s, ConstantLoadConfig& c) {
  // Regressor 1 in L and Y: a constant roll moment L_0 and side force Y_0.
  s.check_keys({"L_0", "Y_0"});
  c.enabled = true;
  c.roll_moment_nm = s.or_zero("L_0", range_of(constant_load_params(), "L_0"));
  c.side_force_n = s.or_zero("Y_0", range_of(constant_load_params(), "Y_0"));
}

EffectSizing constant_load_sizing() {
  return {"L_0", "N m", range_of(constant_load_params(), "L_0"), "Y_0 keeps its ratio to the moment",
          [](const YAML::Node& section, double size) {
            return with_companion_ratio(section, size, "L_0", "Y_0", range_of(constant_load_params(), "Y_0"), 0.0);
          }};
}

Effect constant_load_effect() {
  Effect e;
  e.definition = {"constant_load",
                  "a constant roll moment and side force (an offset trim: an asymmetric mass or wing) with "
                  "no bias of the rate gyro (p agrees with phi's derivative)",
                  {},
                  {{"L", "L_0", "1", ColumnForm::kTerm, "1", "N m", range_of(constant_load_params(), "L_0")},
                   {"Y", "Y_0", "1", ColumnForm::kTerm, "1", "N", range_of(constant_load_params(), "Y_0")}},
                  Scan::kNone,
                  Signature::kConstantLoad,
                  EffectivenessChange::kNone,
                  "plant.effects.constant_load: constant roll moment L_0 and side force Y_0"};
  e.from_model = config_from_model(constant_load_from_model);
  e.plant = table_plant_side(constant_load_from, constant_load_params);
  e.plant.make = [](const EffectsConfig& fx, ProcessContext&) {
    return load_process<ConstantLoadConfig>(
        fx.get<ConstantLoadConfig>(),
        [](const ConstantLoadConfig& c, const LoadInputs&, double& L, double& Y) { add_constant_load(c, L, Y); });
  };
  e.plant.sizing = constant_load_sizing;
  return e;
}

}  // namespace nimble::effects
