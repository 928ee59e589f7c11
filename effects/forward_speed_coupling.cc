#include "effects/forward_speed_coupling.h"

#include <stdexcept>

namespace nimble::effects {

const ParamTable<ForwardSpeedCouplingConfig>& forward_speed_coupling_params() {
  using C = ForwardSpeedCouplingConfig;
  static const ParamTable<C> table = {
      {"enabled", &C::enabled, Range::any(), "-", "fly the effect (required)"},
      {"gain_per_mps", &C::gain_per_mps, Range::closed(-2.0, 2.0), "1/(m/s)",
       "the lateral stability derivatives scale with 1 + k (u - u0) (or give the four coefficients)"},
      {"L_up", &C::L_up_ns2, Range::closed(-0.1, 0.1), "N s^2", "L += L_up (u - u0) p"},
      {"L_uv", &C::L_uv_ns2pm, Range::closed(-0.1, 0.1), "N s^2/m", "L += L_uv (u - u0) v"},
      {"Y_up", &C::Y_up_ns2pm, Range::closed(-1.0, 1.0), "N s^2/m", "Y += Y_up (u - u0) p"},
      {"Y_uv", &C::Y_uv_ns2pm2, Range::closed(-1.0, 1.0), "N s^2/m^2", "Y += Y_uv (u - u0) v"},
  };
  return table;
}

ForwardSpeedCouplingConfig forward_speed_coupling_from(ConfigMap& map) {
  ForwardSpeedCouplingConfig c;
  c.enabled = map.get_bool("enabled");
  // One form or the other: a gain on the stability derivatives, or the four coefficients.
  const bool gain = map.has("gain_per_mps");
  std::string coefficient;
  for (const char* key : {"L_up", "L_uv", "Y_up", "Y_uv"}) {
    if (map.has(key) && coefficient.empty()) coefficient = key;
  }
  if (gain && !coefficient.empty()) {
    map.fail("gain_per_mps",
             "give either gain_per_mps or the coefficients L_up, L_uv, Y_up, "
             "Y_uv, not both (" +
                 coefficient + " is given too)");
  }
  read_params(map, forward_speed_coupling_params(), c);
  return c;
}

void forward_speed_coupling_from_model(const ModelSection& s, ForwardSpeedCouplingConfig& c) {
  // The workflow's regressors (u - u0) p and (u - u0) v in L and Y: the four-coefficient form,
  // replacing the plant file's gain.
  s.check_keys({"L_up", "L_uv", "Y_up", "Y_uv"});
  const auto& t = forward_speed_coupling_params();
  c.enabled = true;
  c.gain_per_mps = 0.0;
  c.L_up_ns2 = s.or_zero("L_up", range_of(t, "L_up"));
  c.L_uv_ns2pm = s.or_zero("L_uv", range_of(t, "L_uv"));
  c.Y_up_ns2pm = s.or_zero("Y_up", range_of(t, "Y_up"));
  c.Y_uv_ns2pm2 = s.or_zero("Y_uv", range_of(t, "Y_uv"));
}

namespace {

class ForwardSpeedCouplingProcess : public EffectProcess {
 public:
  explicit ForwardSpeedCouplingProcess(const ForwardSpeedCouplingConfig& config) : config_(config) {}
  double stability_factor(double du) const override { return forward_speed_factor(config_, du); }
  void add_loads(const LoadInputs& in, double& L, double& Y) const override {
    add_forward_speed_coupling(config_, in.du, in.p, in.v_rel, L, Y);
  }

 private:
  ForwardSpeedCouplingConfig config_;
};

}  // namespace

std::unique_ptr<EffectProcess> forward_speed_coupling_process(const ForwardSpeedCouplingConfig& config) {
  if (!config.enabled) return nullptr;
  if (config.gain_per_mps != 0.0 && config.has_coefficients()) {
    throw std::invalid_argument(
        "plant: forward_speed_coupling has both gain_per_mps and the coefficients L_up, L_uv, Y_up, Y_uv; give one "
        "form");
  }
  return std::make_unique<ForwardSpeedCouplingProcess>(config);
}

EffectSizing forward_speed_coupling_sizing() {
  return {"gain_per_mps", "1/(m/s)", range_of(forward_speed_coupling_params(), "gain_per_mps"),
          "the explicit coefficients stay as set",
          [](const YAML::Node&, double size) { return parameter_alone("gain_per_mps", size); }};
}

Effect forward_speed_coupling_effect() {
  Effect e;
  e.definition = {"forward_speed_coupling",
                  "(u - u0) p and (u - u0) v: the lateral stability derivatives change with forward speed",
                  {"u"},
                  {{"L", "L_up", "(u - u0) p", ColumnForm::kTerm, "(u - u0)*p"},
                   {"L", "L_uv", "(u - u0) v", ColumnForm::kTerm, "(u - u0)*v"},
                   {"Y", "Y_up", "(u - u0) p", ColumnForm::kTerm, "(u - u0)*p"},
                   {"Y", "Y_uv", "(u - u0) v", ColumnForm::kTerm, "(u - u0)*v"}},
                  Scan::kNone,
                  Signature::kNone,
                  EffectivenessChange::kNone,
                  "plant.effects.forward_speed_coupling, four-coefficient form: L += L_up (u - u0) p + L_uv (u - u0) "
                  "v, Y likewise"};
  e.from_model = config_from_model(forward_speed_coupling_from_model);
  e.plant = table_plant_side(forward_speed_coupling_from, forward_speed_coupling_params);
  e.plant.make = [](const EffectsConfig& fx, ProcessContext&) {
    return forward_speed_coupling_process(fx.get<ForwardSpeedCouplingConfig>());
  };
  e.plant.sizing = forward_speed_coupling_sizing;
  return e;
}

}  // namespace nimble::effects
