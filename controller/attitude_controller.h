#pragma once
/// Attitude controller core of the Delfly Nimble rig: reference generators,
/// PD roll and pitch loops, command low-pass, saturation, mixing to left/right
/// flapping-frequency commands and throttle with tilt compensation.
/// Transport-free: the controller process copies ControllerInput from its
/// messages and ControllerOutput into them (see controller/README.md).
///
/// One step, at the fixed rate rate_hz (default 512 Hz):
///   phi_ref, p_ref     = roll reference generator(roll_sp)
///   theta_ref, q_ref   = pitch reference generator(pitch_sp)
///   roll_cmd   = sat1( LP15( Kp (phi_ref - phi) + Kd (p_ref - p) ) )            [-], gains by name
///   pitch_cmd  = sat1( LP15( Kp_theta (theta_ref - theta) + Kd_theta (q_ref - q) ) ) [-]
///   throttle   = clamp(throttle_sp * throttle_factor, 0, 100)                     [%]
///   delta_t    = throttle - trim_throttle_pct                                     [%]
///   f_c        = f_trim_radps + throttle_to_freq_radps_per_pct * delta_t          [rad/s]
///   delta_f    = roll_cmd_to_delta_f_radps * roll_cmd                             [rad/s]
///   left/right = f_c +- delta_f / 2 + roll_cmd_to_delta_f_radps * mix_abs_roll_gain * |roll_cmd|
///   dihedral   = pitch_cmd_to_dihedral_rad * pitch_cmd                           [rad]
///   yaw_cmd    = sat1( LP15( Kp_psi (0 - psi) + Kd_psi (0 - r) ) )   (yaw.enabled)     [-]
///   wing_root  = yaw_cmd_to_wing_root_rad * yaw_cmd                               [rad]
/// which is the onboard mixing left/right = thrust +- 0.5 roll + 0.1 |roll| with one
/// normalised motor unit worth roll_cmd_to_delta_f_radps of flapping frequency.

#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "contract/rates.h"
#include "controller/low_pass.h"
#include "controller/reference_generator.h"
#include "core/config.h"
#include "core/param_table.h"
#include "core/thrust_curve.h"

namespace nimble {

/// Thrust of both flapping wing pairs [N] at flapping frequency `f_radps` [rad/s]: the
/// published curve of core/thrust_curve.h, T = 2 (0.0114 f_hz - 0.0449) (thesis Eq 4.18).
double flap_thrust_n(double f_radps);

/// Flapping frequency [rad/s] at which the published thrust curve (core/thrust_curve.h)
/// equals the weight mass_kg * gravity_mps2.
/// @throws std::invalid_argument if mass_kg or gravity_mps2 is not positive and finite.
double hover_flap_frequency_radps(double mass_kg, double gravity_mps2);

/// PD gains of one attitude loop (parameters: gain_params()).
struct GainSet {
  /// Proportional gain [1/rad]: normalised command per rad of angle error.
  double kp_per_rad = 0.0;
  /// Derivative gain [s/rad]: normalised command per rad/s of rate error.
  double kd_per_radps = 0.0;
};

/// Every parameter of the attitude controller, with the rig's defaults.
/// Sources and assumptions: rig_configs/controller/nimble_attitude.yaml.
struct ControllerConfig {
  /// Control rate [Hz]; the onboard loop and the IMU run at 512 Hz.
  double rate_hz = contract::kDefaultControlRateHz;
  /// Roll reference generator (onboard int_euler values).
  ReferenceGeneratorConfig roll_reference{};
  /// Pitch reference generator (onboard int_euler values).
  ReferenceGeneratorConfig pitch_reference{};
  /// Cut-off of the roll command low-pass [Hz].
  double roll_lowpass_cutoff_hz = 15.0;
  /// Cut-off of the pitch command low-pass [Hz].
  double pitch_lowpass_cutoff_hz = 15.0;
  /// Roll gain sets by name: 'fast' (thesis Table 7.1 open-loop) and 'slow'
  /// (closed-loop, onboard 3000/4800 and 750/4800); users may add more.
  std::map<std::string, GainSet> roll_gain_sets{{"fast", {1.406, 0.200}}, {"slow", {0.625, 0.156}}};
  /// Gain set active after construction and reset.
  std::string default_gain_set = "fast";
  /// Pitch PD gains (not published; calibrated on the linear pitch loop of the thesis
  /// Table E.4 model with pitch_cmd_to_dihedral_rad 0.35: calibrate_pitch_gains, see
  /// rig_configs/controller/nimble_attitude.yaml).
  GainSet pitch_gains{0.115, 0.011};
  /// delta_f command per unit normalised roll command [rad/s] (not published; calibrated
  /// on the linear closed loop, see rig_configs/controller/nimble_attitude.yaml).
  double roll_cmd_to_delta_f_radps = 125.0;
  /// Weight of |roll_cmd| added to both wings by the onboard mixing [-].
  double mix_abs_roll_gain = 0.1;
  /// Dihedral deflection per unit normalised pitch command [rad] (assumption).
  double pitch_cmd_to_dihedral_rad = 0.35;
  /// Yaw loop (thesis Fig 2.9 C: the yaw angle through the wing-root servo). Off by default:
  /// the three-state models have no yaw; on for the four-state model (rig_configs/yaw/).
  bool yaw_enabled = false;
  /// Yaw PD gains (not published, "found by trial and error"; calibrated on the linear roll-yaw
  /// loop of the Table 8.3 model: calibrate_yaw_gains, rig_configs/controller/nimble_attitude.yaml).
  GainSet yaw_gains{0.16, 0.82};
  /// Wing-root deflection per unit normalised yaw command [rad] (assumption: 0.35 rad full scale,
  /// as the dihedral). Negative: N_dw of Table 8.3 is negative, so a positive wing-root angle
  /// yaws the nose left, and a positive yaw command asks for nose right.
  double yaw_cmd_to_wing_root_rad = -0.35;
  /// Throttle at hover trim [% of full scale] (assumption).
  double trim_throttle_pct = 60.0;
  /// Flapping frequency at hover trim [rad/s]: thrust = weight for the vehicle
  /// without wifi module (28.76 g, g = 9.81 m/s^2).
  double f_trim_radps = 102.49738145337824;
  /// Collective flapping frequency per % of throttle deviation [rad/s/%]
  /// (assumption: frequency proportional to throttle, f_trim / trim_throttle_pct).
  double throttle_to_freq_radps_per_pct = 102.49738145337824 / 60.0;
  /// Lower limit of each wing's flapping-frequency command [rad/s].
  double flap_freq_min_radps = 0.0;
  /// Upper limit of each wing's flapping-frequency command [rad/s] (software safety limit).
  double flap_freq_max_radps = 200.0;

  /// Failsafe: the input (TRUTH or ESTIMATE; for an estimate, the time of the IMU sample it
  /// rests on) is stale when older than this [s]. 50 ms: about 25 control cycles at 512 Hz, ten
  /// times the motion-capture latency the EKF is built for (assumption: no published figure).
  double input_stale_s = 0.05;
  /// Failsafe: no input at all by this simulated time [s] engages it too. 0.5 s: the estimator's
  /// first estimate follows its first motion-capture pose within milliseconds (assumption).
  double first_input_timeout_s = 0.5;
  /// Failsafe throttle [%]: with neutral roll and pitch commands, a slow descent. 57 %: about
  /// 0.65 m/s^2 of thrust below the weight (thesis Eq 4.18 with the collective map above).
  double failsafe_throttle_pct = 57.0;

  /// Control period 1 / rate_hz [s].
  double dt_s() const { return 1.0 / rate_hz; }
};

/// Checks a controller configuration.
/// @throws std::invalid_argument naming the first bad parameter, its value and the allowed range.
void validate(const ControllerConfig& config);

/// The controller section's single-valued parameters (key group.name within its sub-mapping,
/// range, unit, meaning; defaults: ControllerConfig's or the base file's). The loader,
/// validate() and `rig params` use the tables; the low-pass cut-offs (below Nyquist of rate_hz),
/// the gain-set map and default_gain_set are read and checked on their own.
const ParamTable<ControllerConfig>& controller_params();
/// Each axis of `reference` (roll, pitch).
const ParamTable<ReferenceGeneratorConfig>& reference_params();
/// Each gain set (roll_gain_sets.<name>, pitch_gains).
const ParamTable<GainSet>& gain_params();

/// Gains of the roll gain set `name`.
/// @throws std::invalid_argument naming `name` and the known sets if there is none of that name.
const GainSet& roll_gain_set(const ControllerConfig& config, const std::string& name);

/// Reads a controller configuration from `map` over `base` (keys absent from the
/// map keep the value of `base`), then checks it and that no key is unknown.
/// Gain sets in the map replace same-named sets of `base` and add new ones.
/// @throws ConfigError naming file, key, value and the allowed range.
ControllerConfig controller_config_from(ConfigMap& map, const ControllerConfig& base = ControllerConfig{});

/// Loads a controller configuration file (rig_configs/controller/*.yaml) over the defaults.
/// @throws ConfigError as controller_config_from.
ControllerConfig load_controller_config(const std::string& file);

/// Inputs of one control step: measured attitude and rates, set-points.
struct ControllerInput {
  double phi_rad = 0.0;       ///< measured roll angle [rad], positive right wing down
  double theta_rad = 0.0;     ///< measured pitch angle [rad], positive nose up
  double p_radps = 0.0;       ///< measured roll rate, body x [rad/s]
  double q_radps = 0.0;       ///< measured pitch rate, body y [rad/s]
  double roll_sp_rad = 0.0;   ///< roll set-point [rad]
  double pitch_sp_rad = 0.0;  ///< pitch set-point [rad]
  /// Throttle set-point before tilt compensation [% of full scale, 0..100]
  /// (attitude_setpoint_t.throttle_pct). Not finite (the default): trim throttle.
  double throttle_pct = std::numeric_limits<double>::quiet_NaN();
  /// Tilt compensation factor THRF [-], >= 1 (attitude_setpoint_t.throttle_factor).
  double throttle_factor = 1.0;
  double psi_rad = 0.0;  ///< measured yaw angle [rad] (yaw loop)
  double r_radps = 0.0;  ///< measured yaw rate, body z [rad/s] (yaw loop)
};

/// Outputs of one control step.
struct ControllerOutput {
  double flap_freq_left_radps = 0.0;   ///< left wing flapping-frequency command [rad/s]
  double flap_freq_right_radps = 0.0;  ///< right wing flapping-frequency command [rad/s]
  double delta_f_cmd_radps = 0.0;      ///< left - right [rad/s]; positive rolls right wing down
  double collective_radps = 0.0;       ///< (left + right) / 2 [rad/s]
  double throttle_cmd_pct = 0.0;       ///< throttle after tilt compensation [%, 0..100]
  double delta_throttle_pct = 0.0;     ///< throttle_cmd_pct - trim_throttle_pct: the model's delta_t [%]
  double dihedral_rad = 0.0;           ///< dihedral servo command [rad], positive nose-up moment
  double wing_root_rad = 0.0;          ///< wing-root servo command [rad]; 0 without the yaw loop
  double yaw_cmd_norm = 0.0;           ///< yaw command after low-pass and saturation [-], -1..1
  double roll_cmd_norm = 0.0;          ///< roll command after low-pass and saturation [-], -1..1
  double pitch_cmd_norm = 0.0;         ///< pitch command after low-pass and saturation [-], -1..1
  double roll_ref_rad = 0.0;           ///< roll reference [rad]
  double roll_rate_ref_radps = 0.0;    ///< roll-rate reference [rad/s]
  double pitch_ref_rad = 0.0;          ///< pitch reference [rad]
  double pitch_rate_ref_radps = 0.0;   ///< pitch-rate reference [rad/s]
  double roll_error_rad = 0.0;         ///< roll_ref - phi [rad]
  double pitch_error_rad = 0.0;        ///< pitch_ref - theta [rad]
  double roll_kp_per_rad = 0.0;        ///< roll P gain in use [1/rad]
  double roll_kd_per_radps = 0.0;      ///< roll D gain in use [s/rad]
  bool saturated = false;              ///< any command clipped at its limit in this step
};

/// Event counters since construction or reset_counters().
struct ControllerCounters {
  std::int64_t steps = 0;                      ///< control steps taken
  std::int64_t saturated_steps = 0;            ///< steps with any clipped command
  std::int64_t roll_saturations = 0;           ///< steps with |roll_cmd| clipped to 1
  std::int64_t pitch_saturations = 0;          ///< steps with |pitch_cmd| clipped to 1
  std::int64_t yaw_saturations = 0;            ///< steps with |yaw_cmd| clipped to 1
  std::int64_t throttle_saturations = 0;       ///< steps with throttle or throttle factor clipped
  std::int64_t flap_freq_saturations = 0;      ///< steps with a wing frequency clipped
  std::int64_t invalid_inputs = 0;             ///< steps with a non-finite measured value or set-point
  std::int64_t setpoint_clamps = 0;            ///< set-points clamped by the reference generators
  std::int64_t unknown_gain_set_requests = 0;  ///< select_gain_set calls with an unknown name
};

/// PD attitude controller at a fixed step dt = 1 / rate_hz.
class AttitudeController {
 public:
  /// @throws std::invalid_argument if the configuration is invalid (see validate()).
  explicit AttitudeController(const ControllerConfig& config);

  /// One control step. Never throws: non-finite inputs are replaced by their
  /// last finite value (counted), commands are clipped at their limits (counted).
  ControllerOutput step(const ControllerInput& in);

  /// The failsafe's command, without state feedback: zero roll and pitch commands (the wings
  /// neutral, no differential flapping) at `throttle_pct`. Resets the command filters, so that
  /// a step() after it starts from rest.
  ControllerOutput failsafe_output(double throttle_pct);

  /// Selects the roll gain set `name`. Never throws: an unknown name keeps the
  /// active set, is counted and returns false.
  bool select_gain_set(const std::string& name);
  /// Name of the active roll gain set.
  const std::string& gain_set() const { return gain_set_name_; }
  /// Gains of the active roll gain set.
  const GainSet& gains() const { return gains_; }

  /// Restarts references at rest at the given attitude [rad], clears filters,
  /// and selects the default gain set. Counters are kept.
  void reset(double phi_rad = 0.0, double theta_rad = 0.0);
  /// Zeroes the counters.
  void reset_counters() { counters_ = ControllerCounters{}; }

  /// Event counters.
  const ControllerCounters& counters() const { return counters_; }
  /// Configuration in use.
  const ControllerConfig& config() const { return config_; }
  /// Control period [s].
  double dt_s() const { return config_.dt_s(); }

 private:
  double sanitize(double value, double& last, bool& invalid);

  ControllerConfig config_;
  ReferenceGenerator roll_ref_, pitch_ref_;
  SecondOrderLowPass roll_lp_, pitch_lp_, yaw_lp_;
  std::string gain_set_name_;
  GainSet gains_;
  ControllerCounters counters_;
  // last finite values of the inputs
  double last_phi_ = 0.0, last_theta_ = 0.0, last_p_ = 0.0, last_q_ = 0.0, last_psi_ = 0.0, last_r_ = 0.0;
  double last_roll_sp_ = 0.0, last_pitch_sp_ = 0.0, last_factor_ = 1.0;
};

}  // namespace nimble
