#include "effects/lateral_gust.h"

#include <cmath>
#include <stdexcept>

#include "turbulence/discretisation.h"
#include "turbulence/dryden.h"
#include "turbulence/lyapunov.h"

namespace nimble::effects {

std::string to_string(GustForm form) { return form == GustForm::kDryden ? "dryden" : "gauss_markov"; }

const ParamTable<LateralGustConfig>& lateral_gust_params() {
  using C = LateralGustConfig;
  static const ParamTable<C> table = {
      {"enabled", &C::enabled, Range::any(), "-", "fly the effect (required)"},
      {"sigma_mps", &C::sigma_mps, Range::closed(0.0, 5.0), "m/s", "standard deviation of the side wind"},
      {"tau_s", &C::tau_s, Range{0.0, 100.0, true, false}, "s", "gauss_markov: correlation time"},
      {"time_scale_s", &C::time_scale_s, Range{0.0, 100.0, true, false}, "s", "dryden: time scale T"},
  };
  return table;
}

LateralGustConfig lateral_gust_from(ConfigMap& map) {
  LateralGustConfig c;
  c.enabled = map.get_bool("enabled");
  read_params(map, lateral_gust_params(), c);
  const std::string form = map.has("form") ? map.get_enum("form", {"gauss_markov", "dryden"}) : "gauss_markov";
  c.form = form == "dryden" ? GustForm::kDryden : GustForm::kGaussMarkov;
  return c;
}

void lateral_gust_from_model(const ModelSection& s, LateralGustConfig& c) {
  // No regressor: named from the residual spectrum with the plant's first-order Gauss-Markov
  // parameters.
  s.check_keys({"sigma_mps", "tau_s"});
  c.enabled = true;
  c.form = GustForm::kGaussMarkov;
  c.sigma_mps = s.required("sigma_mps", range_of(lateral_gust_params(), "sigma_mps"));
  c.tau_s = s.required("tau_s", range_of(lateral_gust_params(), "tau_s"));
}

namespace {

class LateralGustProcess : public EffectProcess {
 public:
  explicit LateralGustProcess(const GustProcess& gust) : gust_(gust) {}
  double side_wind_mps() const override { return gust_.velocity_mps(); }
  void step(double h, std::mt19937_64& rng, std::normal_distribution<double>& normal) override {
    gust_.step(h, rng, normal);
  }

 private:
  GustProcess gust_;
};

}  // namespace

std::unique_ptr<EffectProcess> lateral_gust_process(const LateralGustConfig& config, ProcessContext& context) {
  if (!config.enabled) return nullptr;
  return std::make_unique<LateralGustProcess>(GustProcess(config, context.dt_s, context.rng, context.normal));
}

GustProcess::GustProcess(const LateralGustConfig& config, double dt_s, std::mt19937_64& rng,
                         std::normal_distribution<double>& normal)
    : c_(config) {
  if (!c_.enabled || c_.form != GustForm::kDryden) return;
  if (!(c_.sigma_mps >= 0.0) || !(c_.time_scale_s > 0.0) || !std::isfinite(c_.time_scale_s)) {
    throw std::invalid_argument("plant: effects.lateral_gust (dryden) needs sigma_mps >= 0 and time_scale_s > 0");
  }
  // The unit-sigma filter, scaled by sigma on the output (sigma = 0 is a silent gust with the
  // same random stream).
  const turbulence::ShapingFilter f = turbulence::time_based_second_order(1.0, c_.time_scale_s);
  const Eigen::VectorXd unit = Eigen::VectorXd::Ones(1);
  const turbulence::DiscreteModel d = turbulence::discretise(f.system, unit, dt_s);
  Phi_ = d.Phi;
  L_ = d.noise_factor;
  C_ = c_.sigma_mps * f.system.C;
  const Eigen::Matrix2d P = turbulence::stationary_covariance(f.system, unit);
  const Eigen::Matrix2d P_factor = turbulence::psd_factor(P);
  const double n0 = normal(rng), n1 = normal(rng);
  z_ = P_factor * Eigen::Vector2d(n0, n1);
  v_ = (C_ * z_)(0);
}

void GustProcess::step(double h, std::mt19937_64& rng, std::normal_distribution<double>& normal) {
  // Exactly discretised: the first-order Gauss-Markov process, or the Dryden filter with the
  // exact process noise of one plant step (drawn in a fixed order).
  if (!c_.enabled) return;
  if (c_.form == GustForm::kDryden) {
    const double n0 = normal(rng), n1 = normal(rng);
    z_ = Phi_ * z_ + L_ * Eigen::Vector2d(n0, n1);
    v_ = (C_ * z_)(0);
  } else {
    const double a = std::exp(-h / c_.tau_s);
    v_ = a * v_ + c_.sigma_mps * std::sqrt(1.0 - a * a) * normal(rng);
  }
}

EffectSizing lateral_gust_sizing() {
  return {"sigma_mps", "m/s", range_of(lateral_gust_params(), "sigma_mps"), "form, tau_s and time_scale_s stay as set",
          [](const YAML::Node&, double size) { return parameter_alone("sigma_mps", size); }};
}

Effect lateral_gust_effect() {
  Effect e;
  e.definition = {"lateral_gust",
                  "an unmeasured side wind v_g: the aerodynamics see v - v_g, so the side-force equation carries "
                  "-Yv v_g, a low-frequency random force. Stochastic, no regressor: named from its signature in the "
                  "residual spectrum (parameters sigma_mps, tau_s)",
                  {},
                  {},
                  Scan::kNone,
                  Signature::kResidualSpectrum,
                  EffectivenessChange::kNone,
                  "plant.effects.lateral_gust (Gauss-Markov, sigma_mps and tau_s)"};
  e.from_model = config_from_model(lateral_gust_from_model);
  e.plant = table_plant_side(lateral_gust_from, lateral_gust_params);
  e.plant.markdown_rows = [](const std::string& prefix) {
    return params_markdown_rows(lateral_gust_params(), LateralGustConfig{}, prefix) + "| `" + prefix +
           "form` | gauss_markov | gauss_markov, dryden | - | the gust's spectrum (lateral_gust.h) |\n";
  };
  e.plant.make = [](const EffectsConfig& fx, ProcessContext& c) {
    return lateral_gust_process(fx.get<LateralGustConfig>(), c);
  };
  e.plant.sizing = lateral_gust_sizing;
  return e;
}

}  // namespace nimble::effects
