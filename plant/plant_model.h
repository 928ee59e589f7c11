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

#include "core/config.h"
#include "core/model.h"
#include "core/param_table.h"
#include "core/rig_values.h"
#include "core/thrust_curve.h"
#include "core/vehicle.h"

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

/// Periodic forcing at the flapping frequency and its harmonics (thesis §7: oscillations at
/// hover not captured by the linear model). Amplitude h-1 of the list acts at h times the
/// flapping frequency of the actual collective (about 16-17 Hz at trim), phase-locked to the
/// plant's flapping phase; the phases relative to it are drawn from the seed.
struct FlappingForcingConfig {
  bool enabled = false;
  std::vector<double> roll_moment_amplitudes_nm;  ///< per harmonic [N m]
  std::vector<double> side_force_amplitudes_n;    ///< per harmonic [N]
};

/// Lateral-inflow nonlinearity: Y += Y_vv v|v|, L += L_vv v|v| (sideways flight, thesis §9.5).
///
/// Each effect below can also come from the lateral model: an effect its `effects:` section
/// carries (rig discrepancy --model-out) overrides the plant file's effect of the same name
/// with the model's coefficients; plant/model_effects.h apply_model_effects() has the mapping
/// for every effect name (lateral_inflow: Y_vv, L_vv; forward_speed_coupling; actuator_delay;
/// flapping_forcing; sensor_bias as constant_load; lateral_gust; dihedral_coupling and
/// yaw_coupling as derivatives; kinematic_coupling and gravity_nonlinearity are in the
/// equations of motion already).
struct LateralInflowConfig {
  bool enabled = false;
  double Y_vv_ns2pm2 = 0.0;  ///< [N s^2/m^2]
  double L_vv_ns2pm = 0.0;   ///< [N m s^2/m^2]
};

/// Forward-speed coupling, in one of two forms (not both: the config reader and the
/// PlantModel constructor refuse a gain together with a coefficient):
///  - one gain k: the lateral stability derivatives (L, N and Y rows) scale with (1 + k (u - u0));
///  - four coefficients (the discrepancy workflow's regressors): L += L_up (u - u0) p +
///    L_uv (u - u0) v, Y += Y_up (u - u0) p + Y_uv (u - u0) v.
/// For a lateral3 model (r = 0, no N row) the gain k is the same as L_up = k Lp, L_uv = k Lv,
/// Y_up = k Yp, Y_uv = k Yv. u0 is the lateral model's trim; v is relative to the lateral gust,
/// as in the rest of the aerodynamics. u moves only with a longitudinal model (otherwise it is
/// held at trim and the effect is inert).
struct ForwardSpeedCouplingConfig {
  bool enabled = false;
  double gain_per_mps = 0.0;  ///< k [1/(m/s)]
  double L_up_ns2 = 0.0;      ///< [N m per (m/s) (rad/s)] = [N s^2]
  double L_uv_ns2pm = 0.0;    ///< [N m per (m/s)^2] = [N s^2/m]
  double Y_up_ns2pm = 0.0;    ///< [N per (m/s) (rad/s)] = [N s^2/m]
  double Y_uv_ns2pm2 = 0.0;   ///< [N per (m/s)^2] = [N s^2/m^2]
  /// True when any of the four coefficients is non-zero.
  bool has_coefficients() const {
    return L_up_ns2 != 0.0 || L_uv_ns2pm != 0.0 || Y_up_ns2pm != 0.0 || Y_uv_ns2pm2 != 0.0;
  }
};

/// Pure delay on every actuator command (flap frequencies and servos).
struct ActuatorDelayConfig {
  bool enabled = false;
  double delay_s = 0.0;
};

/// Form of the lateral gust's spectrum (key `form`; not `model`, which scenario loading
/// treats as a file path at any depth).
enum class GustForm {
  kGaussMarkov,  ///< first order: S(omega) = 2 sigma^2 tau / (1 + (omega tau)^2)
  kDryden,       ///< time-based second-order Dryden lateral form (turbulence/dryden.h)
};

/// "gauss_markov" or "dryden".
std::string to_string(GustForm form);

/// Lateral gust: side wind v_g with standard deviation sigma; aerodynamics see v - v_g (the
/// Lv, Yv (and Nv) terms and every effect of v act on the relative velocity).
///  - gauss_markov (default): first-order Gauss-Markov with correlation time tau_s, starting
///    at v_g = 0, one normal draw per plant step;
///  - dryden: the time-based second-order Dryden lateral form of turbulence/dryden.h,
///    S(omega) = sigma^2 T (1 + 3 (omega T)^2) / (1 + (omega T)^2)^2 with T = time_scale_s
///    (the frozen-field form's T = L_v / V: a hovering vehicle has no airspeed to fly through
///    the turbulence, so the time scale is the parameter), discretised exactly at the plant
///    rate (ZOH and Van Loan, turbulence/discretisation.h): its sampled variance is sigma^2
///    at any rate. Starts stationary (filter state drawn from its covariance, two normal draws
///    in the constructor), then two normal draws per plant step.
/// The plant file's defaults and where they come from: rig_configs/plant/nimble_plant.yaml.
struct LateralGustConfig {
  bool enabled = false;
  double sigma_mps = 0.0;
  double tau_s = 1.0;                          ///< Gauss-Markov correlation time [s]
  GustForm form = GustForm::kGaussMarkov;       ///< key `form`: gauss_markov | dryden
  double time_scale_s = 1.0;                   ///< Dryden time scale T [s]
};

/// Constant roll moment and side force (L += roll_moment_nm, Y += side_force_n). Flies a model's
/// sensor_bias (L_0, Y_0): the equation-error regression cannot tell a rate-sensor bias from a
/// constant moment, and the plant flies the moment/force form.
struct ConstantLoadConfig {
  bool enabled = false;
  double roll_moment_nm = 0.0;  ///< [N m]
  double side_force_n = 0.0;    ///< [N]
};

struct EffectsConfig {
  FlappingForcingConfig flapping_forcing;
  LateralInflowConfig lateral_inflow;
  ForwardSpeedCouplingConfig forward_speed_coupling;
  ActuatorDelayConfig actuator_delay;
  LateralGustConfig lateral_gust;
  ConstantLoadConfig constant_load;
};

/// Initial perturbation from trim. q, r, u and theta apply only where they are states
/// (q, u, theta with a longitudinal model; r with a lateral4 model).
struct InitialState {
  double p_radps = 0.0, q_radps = 0.0, r_radps = 0.0;
  double u_mps = 0.0, v_mps = 0.0;
  double phi_rad = 0.0, theta_rad = 0.0;
};

/// Everything the plant model needs besides the derivative models and the vehicle.
struct PlantConfig {
  double rate_hz = 1000.0;           ///< integration rate [Hz]
  double truth_rate_hz = 1000.0;     ///< TRUTH publication rate [Hz]
  double feedback_rate_hz = 100.0;   ///< ACTUATOR_FB publication rate [Hz]
  double command_timeout_s = 0.1;    ///< hold the safe state when commands stop this long [s]
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
  uint64_t seed = 1;
};

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

/// Actuator command as the plant receives it.
struct ActuatorInput {
  double flap_freq_left_radps = 0.0;
  double flap_freq_right_radps = 0.0;
  double dihedral_rad = 0.0;
  double wing_root_rad = 0.0;
};

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
  PlantModel(const DerivativeModel& lateral, const std::optional<DerivativeModel>& longitudinal,
             const Vehicle& vehicle, const PlantConfig& config);

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
  ActuatorInput delayed(const ActuatorInput& cmd);

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
  double x_gust_ = 0.0;  ///< side gust velocity [m/s]
  // Dryden gust filter, exact discrete form: z_{k+1} = Phi z_k + L n_k, v_g = C z.
  Eigen::Matrix2d gust_Phi_ = Eigen::Matrix2d::Zero(), gust_L_ = Eigen::Matrix2d::Zero();
  Eigen::RowVector2d gust_C_ = Eigen::RowVector2d::Zero();
  Eigen::Vector2d gust_z_ = Eigen::Vector2d::Zero();
  std::vector<double> forcing_phase_roll_, forcing_phase_side_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::deque<std::pair<double, ActuatorInput>> delay_line_;
  Truth truth_;
};

}  // namespace nimble::plant
