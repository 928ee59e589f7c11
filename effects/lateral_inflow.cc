#include "effects/lateral_inflow.h"

namespace nimble::effects {

const ParamTable<LateralInflowConfig>& lateral_inflow_params() {
  using C = LateralInflowConfig;
  static const ParamTable<C> table = {
      {"enabled", &C::enabled, Range::any(), "-", "fly the effect (required)"},
      {"Y_vv", &C::Y_vv_ns2pm2, Range::closed(-1.0, 1.0), "N s^2/m^2", "side force Y_vv v|v|"},
      {"L_vv", &C::L_vv_ns2pm, Range::closed(-0.1, 0.1), "N m s^2/m^2", "roll moment L_vv v|v|"},
  };
  return table;
}

LateralInflowConfig lateral_inflow_from(ConfigMap& map) {
  LateralInflowConfig c;
  c.enabled = map.get_bool("enabled");
  read_params(map, lateral_inflow_params(), c);
  return c;
}

void lateral_inflow_from_model(const ModelSection& s, LateralInflowConfig& c) {
  // L += L_vv v|v|, Y += Y_vv v|v| (v relative to the gust).
  s.check_keys({"L_vv", "Y_vv"});
  c.enabled = true;
  c.L_vv_ns2pm = s.or_zero("L_vv", range_of(lateral_inflow_params(), "L_vv"));
  c.Y_vv_ns2pm2 = s.or_zero("Y_vv", range_of(lateral_inflow_params(), "Y_vv"));
}

EffectSizing lateral_inflow_sizing() {
  return {"Y_vv", "N s^2/m^2", range_of(lateral_inflow_params(), "Y_vv"),
          "L_vv keeps its ratio to Y_vv (0.01 m if Y_vv is 0)", [](const YAML::Node& section, double size) {
            return with_companion_ratio(section, size, "Y_vv", "L_vv", range_of(lateral_inflow_params(), "L_vv"), 0.01);
          }};
}

Effect lateral_inflow_effect() {
  Effect e;
  e.definition = {
      "lateral_inflow",
      "v|v| in side force and roll moment: lateral inflow on the leading-edge vortex in sideways "
      "flight",
      {},
      {{"L", "L_vv", "v|v|", ColumnForm::kTerm, "v*abs(v)", "N m s^2/m^2", range_of(lateral_inflow_params(), "L_vv")},
       {"Y", "Y_vv", "v|v|", ColumnForm::kTerm, "v*abs(v)", "N s^2/m^2", range_of(lateral_inflow_params(), "Y_vv")}},
      Scan::kNone,
      Signature::kInflow,
      EffectivenessChange::kNone,
      "plant.effects.lateral_inflow: L, Y += c v|v|"};
  e.from_model = config_from_model(lateral_inflow_from_model);
  e.plant = table_plant_side(lateral_inflow_from, lateral_inflow_params);
  e.plant.make = [](const EffectsConfig& fx, ProcessContext&) {
    return load_process<LateralInflowConfig>(
        fx.get<LateralInflowConfig>(), [](const LateralInflowConfig& c, const LoadInputs& in, double& L, double& Y) {
          add_lateral_inflow(c, in.v_rel, L, Y);
        });
  };
  e.plant.sizing = lateral_inflow_sizing;
  return e;
}

}  // namespace nimble::effects
