#pragma once
/// Lateral gust: side wind v_g with standard deviation sigma; the aerodynamics see v - v_g (the
/// Lv, Yv (and Nv) terms and every effect of v act on the relative velocity).
///  - gauss_markov (default): first-order Gauss-Markov with correlation time tau_s, starting
///    at v_g = 0, one normal draw per plant step;
///  - dryden: the time-based second-order Dryden lateral form of turbulence/dryden.h,
///    S(omega) = sigma^2 T (1 + 3 (omega T)^2) / (1 + (omega T)^2)^2 with T = time_scale_s
///    (the frozen-field form's T = L_v / V: a hovering vehicle has no airspeed to fly through
///    the turbulence, so the time scale is the parameter), discretised exactly at the plant
///    rate (ZOH and Van Loan, turbulence/discretisation.h): its sampled variance is sigma^2
///    at any rate. Starts stationary (filter state drawn from its covariance, two normal draws
///    when it is made), then two normal draws per plant step.
/// Flies the model effect lateral_gust (sigma_mps, tau_s: Gauss-Markov). The plant file's
/// defaults and where they come from: rig_configs/plant/nimble_plant.yaml.

#include <memory>
#include <random>
#include <string>

#include <Eigen/Core>

#include "core/config.h"
#include "core/param_table.h"
#include "effects/effect_process.h"
#include "effects/effect_sizing.h"
#include "effects/model_section.h"
#include "effects/effect.h"

namespace nimble::effects {

/// Form of the gust's spectrum (key `form`; not `model`, which scenario loading treats as a
/// file path at any depth).
enum class GustForm {
  kGaussMarkov,  ///< first order: S(omega) = 2 sigma^2 tau / (1 + (omega tau)^2)
  kDryden,       ///< time-based second-order Dryden lateral form (turbulence/dryden.h)
};

/// "gauss_markov" or "dryden".
std::string to_string(GustForm form);

struct LateralGustConfig {
  bool enabled = false;
  double sigma_mps = 0.0;
  double tau_s = 1.0;                      ///< Gauss-Markov correlation time [s]
  GustForm form = GustForm::kGaussMarkov;  ///< key `form`: gauss_markov | dryden
  double time_scale_s = 1.0;               ///< Dryden time scale T [s]
};

/// `plant.effects.lateral_gust`: key, range, unit, meaning (`form` is read on its own).
const ParamTable<LateralGustConfig>& lateral_gust_params();

/// Reads the section (enabled is required). @throws ConfigError naming the key.
LateralGustConfig lateral_gust_from(ConfigMap& map);

/// The model effect lateral_gust (sigma_mps and tau_s, both required): the Gauss-Markov form.
void lateral_gust_from_model(const ModelSection& section, LateralGustConfig& config);

/// The gust's process at the plant's step dt_s, drawing from the plant's random stream.
class GustProcess {
 public:
  GustProcess() = default;
  /// A Dryden gust draws its stationary start (two normal draws) here.
  /// @throws std::invalid_argument for a Dryden gust without sigma_mps >= 0 and time_scale_s > 0.
  GustProcess(const LateralGustConfig& config, double dt_s, std::mt19937_64& rng,
              std::normal_distribution<double>& normal);

  /// Advances one plant step of h seconds.
  void step(double h, std::mt19937_64& rng, std::normal_distribution<double>& normal);

  /// The side wind [m/s]; 0 when the effect is off.
  double velocity_mps() const { return v_; }

 private:
  LateralGustConfig c_;
  double v_ = 0.0;
  Eigen::Matrix2d Phi_ = Eigen::Matrix2d::Zero(), L_ = Eigen::Matrix2d::Zero();
  Eigen::RowVector2d C_ = Eigen::RowVector2d::Zero();
  Eigen::Vector2d z_ = Eigen::Vector2d::Zero();
};

/// The effect's process: the gust (a Dryden gust draws its stationary start when it is made) as
/// the side wind the aerodynamics see, one GustProcess step per plant step; none when it is off.
/// @throws std::invalid_argument as GustProcess.
std::unique_ptr<EffectProcess> lateral_gust_process(const LateralGustConfig& config, ProcessContext& context);

/// SIZE sets sigma_mps; form, tau_s and time_scale_s stay as set.
EffectSizing lateral_gust_sizing();

/// The effect's definition, its mapping from a model and its plant section (registry.h).
Effect lateral_gust_effect();

}  // namespace nimble::effects
