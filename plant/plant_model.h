#pragma once
/// PlantModel: nonlinear rigid-body dynamics of the Delfly Nimble near hover with the
/// identified aerodynamic derivatives, the flap and servo actuators, and optional effects
/// that the paper's linear model leaves out. Transport-free; the plant process wraps it.
///
/// Equations of motion: thesis Eq 3.1 (rigid body, body axes x forward, y right, z down).
/// Forces and moments: trim thrust from the flapping frequency, T = 2 (0.0114 f - 0.0449) N
/// with f in Hz, plus the derivative model's perturbation forces and moments
/// (L, N, Y from the lateral model; M, X, Z from an optional longitudinal model).
/// Degrees of freedom the configured models do not describe are held at trim, as the
/// vehicle's own pitch and yaw loops would hold them (lateral3: q, r, u, theta, psi).

#include <cstdint>
#include <deque>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "contract/default_rates.h"
#include "core/config.h"
#include "core/model.h"
#include "core/param_table.h"
#include "core/rig_values.h"
#include "core/term_expression.h"
#include "core/terms.h"
#include "core/thrust_curve.h"
#include "core/vehicle.h"
#include "effects/actuator_input.h"
#include "effects/effects_config.h"
#include "effects/effect_process.h"

namespace nimble::plant {

/// Flap mechanism: the collective follows its command through pole/(s + pole); the
/// flapping-frequency difference through delta_f_gain/(s + pole).
struct FlapActuatorConfig {
  /// delta_f = gain / (s + pole) * delta_f_cmd (thesis Eq 33: 12.56/(s+12.56) scaled by 1/1.4).
  double delta_f_gain_radps = 8.97;
  double pole_radps = 12.56;
};

/// Second-order servo: y = wn^2 / (s^2 + 2 zeta wn s + wn^2) u (thesis: 554.2/(s^2+30.25 s+554.2)).
struct ServoConfig {
  double wn2_rad2ps2 = 554.2;  ///< wn^2 [1/s^2]
  double c1_radps = 30.25;     ///< 2 zeta wn [1/s]
};

/// Thrust of the two wing pairs (thesis Eq 4.18), the curve of core/thrust_curve.h; the
/// plant section's `thrust` may change its coefficients.
using ThrustConfig = ThrustCurve;

/// The plant's effects (FlappingForcingConfig, LateralInflowConfig, ForwardSpeedCouplingConfig,
/// ActuatorDelayConfig, LateralGustConfig, ConstantLoadConfig and EffectsConfig): one file each
/// in effects/. Each can also come from the lateral model: an effect its `effects:`
/// section carries (rig discrepancy --model-out) overrides the plant file's effect of the same
/// name with the model's coefficients (effects/registry.h apply_model_effects()).
using effects::EffectProcess;
using effects::EffectsConfig;

/// Initial perturbation from trim. q, r, u and theta apply only where they are states
/// (q, u, theta with a longitudinal model; r with a lateral4 model).
struct InitialState {
  double p_radps = 0.0, q_radps = 0.0, r_radps = 0.0;
  double u_mps = 0.0, v_mps = 0.0;
  double phi_rad = 0.0, theta_rad = 0.0;
};

/// Everything the plant model needs besides the derivative models and the vehicle.
struct PlantConfig {
  double rate_hz = contract::kDefaultPlantRateHz;              ///< integration rate [Hz]
  double truth_rate_hz = contract::kDefaultTruthRateHz;        ///< TRUTH publication rate [Hz]
  double feedback_rate_hz = contract::kDefaultFeedbackRateHz;  ///< ACTUATOR_FB publication rate [Hz]
  double command_timeout_s = 0.1;                              ///< hold the safe state when commands stop this long [s]
  /// Resolution of the actuator interface: commands are rounded to a multiple of it
  /// (0 = no rounding). Defaults: the CAN frames' resolution (can_bridge/nimble_rig.dbc), so
  /// that the plant flies the same commands over the LCM and the CAN link.
  double flap_command_resolution_radps = 0.01;
  double servo_command_resolution_rad = 1e-4;
  FlapActuatorConfig flap;
  ServoConfig servo;
  ThrustConfig thrust;
  /// Collective flapping frequency per % of throttle [rad/s per %]: converts the actual
  /// collective back to the model's delta_t. Not published; the controller's map
  /// (ControllerConfig::throttle_to_freq_radps_per_pct, trim frequency over trim throttle),
  /// which the scenario check requires, and the value rig_configs/plant/nimble_plant.yaml writes.
  double collective_radps_per_pct = 102.49738145337824 / 60.0;
  /// Vertical aerodynamic damping when no longitudinal model is given [N s/m]
  /// (thesis Table E.4: Zw = -5.9e-3).
  double vertical_damping_Zw_nspm = -5.9e-3;
  InitialState initial;
  EffectsConfig effects;
  /// Generic terms (`terms`, core/terms.h): each adds coefficient * expression to the roll
  /// moment L [N m], the side force Y [N] or the yaw moment N [N m] (N acts with a lateral4
  /// model only), in the grammar of core/term_expression.h; the expression reads the states
  /// and inputs by their flight-data names (plant_term_equations()).
  std::vector<Term> terms;
  uint64_t seed = 1;
};

/// Equations a plant term may name: L, Y, N.
const std::vector<std::string>& plant_term_equations();
/// The `plant.terms` keys as Markdown rows (rig params, docs/configuration.md).
std::string terms_markdown();

/// Reads the `plant:` section of a scenario.
/// @throws ConfigError naming the key.
PlantConfig plant_config_from(ConfigMap& map);

/// The plant section's parameter tables (key, range, unit, meaning; the defaults are the
/// structs'): the loader and `rig params` use them. The effects and the rates' divisibility
/// are read and checked on their own (rig_configs/plant/nimble_plant.yaml documents them).
const ParamTable<PlantConfig>& plant_params();
const ParamTable<FlapActuatorConfig>& flap_actuator_params();  ///< `flap_actuator`
const ParamTable<ServoConfig>& servo_params();                 ///< `servo`
const ParamTable<ThrustCurve>& thrust_params();                ///< `thrust`
const ParamTable<InitialState>& initial_params();              ///< `initial`

/// Actuator command as the plant receives it: effects/actuator_input.h.
using effects::ActuatorInput;

/// Truth of the rigid body and actuators at one instant: the value TRUTH carries
/// (core/rig_values.h).
using nimble::Truth;

class PlantModel {
 public:
  /// @param lateral  the lateral derivative model (lateral3 or lateral4); the effects of its
  ///                 `effects:` section are flown with its coefficients (apply_model_effects())
  /// @param longitudinal optional longitudinal model (q u w theta, input delta_d)
  /// @throws std::invalid_argument if the structures do not fit, if the lateral model's
  ///         effects cannot be flown (naming the model and the effect), or if
  ///         forward_speed_coupling has both a gain and coefficients.
  PlantModel(const DerivativeModel& lateral, const std::optional<DerivativeModel>& longitudinal, const Vehicle& vehicle,
             const PlantConfig& config);

  /// Advances by one integration step of 1/rate_hz with `cmd` held (RK4).
  void step(const ActuatorInput& cmd);

  const Truth& truth() const { return truth_; }
  /// Actuator command that holds trimmed hover (both wings at the trim frequency).
  ActuatorInput trim_command() const;
  /// Hover flapping frequency for thrust = weight [rad/s].
  double trim_flap_frequency_radps() const { return f_trim_radps_; }
  double dt_s() const { return dt_s_; }

  /// Size of the state vector: position, velocity, Euler angles, rates, the two flapping
  /// frequencies, two servos with their rates (plant_model.cc lists them).
  static constexpr int kStateDim = 18;
  /// Fixed size: a plant step allocates nothing.
  using State = Eigen::Matrix<double, kStateDim, 1>;

  /// Full state vector (for tests).
  const State& state() const { return x_; }

 private:
  State derivative(const State& x, const ActuatorInput& u, double t, Eigen::Vector3d* specific_force,
                   Eigen::Vector3d* omega_dot) const;
  void update_truth(const ActuatorInput& u);
  /// The command the actuators see: `cmd` through every effect's command hook.
  ActuatorInput actuated(const ActuatorInput& cmd);
  /// The side wind the aerodynamics see: the sum of the effects' [m/s].
  double side_wind_mps() const;
  /// The signals a term reads at state x, in term_signal_names() order.
  void term_signals(const State& x, double* out) const;

  DerivativeModel lat_;
  std::optional<DerivativeModel> lon_;
  Vehicle veh_;
  PlantConfig cfg_;
  double dt_s_;
  double f_trim_radps_;
  double trim_thrust_n_;
  bool lateral4_;
  // Cached derivatives (0 where the model has none).
  double Lp_ = 0, Lr_ = 0, Lv_ = 0, Np_ = 0, Nr_ = 0, Nv_ = 0, Yp_ = 0, Yr_ = 0, Yv_ = 0;
  double L_df_ = 0, L_dt_ = 0, L_dd_ = 0, L_dw_ = 0;
  double N_df_ = 0, N_dt_ = 0, N_dd_ = 0, N_dw_ = 0;
  double Y_df_ = 0, Y_dt_ = 0, Y_dd_ = 0, Y_dw_ = 0;
  double Mq_ = 0, Mu_ = 0, Mw_ = 0, M_dd_ = 0, Xq_ = 0, Xu_ = 0, Xw_ = 0, X_dd_ = 0;
  double Zq_ = 0, Zu_ = 0, Zw_ = 0, Z_dd_ = 0;
  bool active_q_ = false, active_r_ = false, active_u_ = false;

  State x_;
  double t_s_ = 0.0;
  double flap_phase_rad_ = 0.0;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  /// The process of every effect that acts (effects/registry.h), in the registry's order.
  std::vector<std::unique_ptr<EffectProcess>> effects_;
  /// The plant's terms and the lateral model's (config.terms, then the model's terms: section):
  /// programs bound to term_signal_names(), their equation (0 L, 1 Y, 2 N) and coefficient. The
  /// programs' stateful operators move once per step (step()), not per Runge-Kutta stage.
  mutable std::vector<TermProgram> term_programs_;
  std::vector<int> term_equation_;
  std::vector<double> term_coefficient_;
  Truth truth_;
};

}  // namespace nimble::plant
