#pragma once
/// The rig's roll loop as a linear sampled system: what `rig loop` analyses and designs on.
///
/// One control period T = 1 / rate_hz (512 Hz), exactly in discrete time:
///   aircraft   x = [p v phi] of a lateral3 model (core/model.h build_state_space); delta_t is
///              the pilot's and not part of the loop
///   actuator   delta_f = flap_gain / (s + flap_pole) delta_f_applied         (thesis Eq 33)
///   hold       the command issued at step k is applied from kT + latency on, held until the
///              next one (zero-order hold); latency = n T + f, 0 <= f < T, by the modified
///              z-transform: x[k+1] = Ad x[k] + G1 u[k-n-1] + G0 u[k-n] with
///              G0 = int_0^{T-f} e^{As} ds B and G1 = e^{A(T-f)} int_0^f e^{As} ds B
///   controller phi_ref, p_ref = the reference generator (controller/reference_generator.h,
///              its onboard Euler steps, without its limits)
///              pd   = kp (phi_ref - phi) + kd (p_ref - p)
///              cmd  = LP(pd), the 15 Hz Butterworth's difference equation (low_pass.h)
///              delta_f_cmd = roll_cmd_to_delta_f_radps cmd
/// Left out, and noted by `rig loop`: the clip of |cmd| at 1 (|delta_f_cmd| at
/// roll_cmd_to_delta_f_radps), the flapping-frequency limits, the |roll_cmd| term of the
/// mixing (collective, not roll), sin(phi) against phi, and the plant's nonlinear effects.
///
/// The rig's timing, measured on its logs: in process and lockstep the controller's input is
/// the TRUTH of the plant step it runs at and its command acts from that step on (latency 0);
/// flying on the estimate, the IMU sample reaches the estimator one control period later and
/// its estimate the controller one more (mean 3.907 ms = 2 T over a run). The plant's
/// actuator_delay effect adds its delay, rounded up to whole plant steps.
///
/// State of the broken loop: [p v phi delta_f | u[k-1] .. u[k-m] | s1 s2 of the low-pass];
/// of the set-point loop the same, then the reference generator's [angle rate accel].

#include <complex>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "contract/rates.h"
#include "controller/attitude_controller.h"
#include "controller/loop_margins.h"
#include "controller/reference_generator.h"
#include "core/model.h"

namespace nimble {

/// Where the roll loop is broken for its margins.
enum class LoopBreak {
  kActuator,  ///< at the actuator command delta_f_cmd (the loop's one input)
  kPhi,       ///< at the roll angle the controller measures, the rate loop closed
  kP,         ///< at the roll rate the controller measures, the angle loop closed
};

/// "actuator", "phi", "p".
std::string to_string(LoopBreak b);

/// Everything of the roll loop besides the aircraft model.
struct RollLoopConfig {
  GainSet gains;                                     ///< roll PD gains
  double rate_hz = contract::kDefaultControlRateHz;  ///< control rate [Hz]
  double lowpass_cutoff_hz = 15.0;                   ///< Butterworth cut-off of the roll command [Hz]
  double roll_cmd_to_delta_f_radps = 125.0;          ///< delta_f_cmd per unit command [rad/s]
  double flap_gain_per_s = 8.97;                     ///< flap actuator numerator [1/s] (thesis Eq 33)
  double flap_pole_radps = 12.56;                    ///< flap actuator pole [rad/s] (thesis Eq 33)
  double latency_s = 0.0;                            ///< from the measurement to the command's action [s]
  ReferenceGeneratorConfig reference;                ///< the roll reference generator
};

/// The roll part of a controller configuration with the gains `gains`; flap actuator: defaults.
RollLoopConfig roll_loop_config(const ControllerConfig& controller, const GainSet& gains);

/// The aircraft model and actuator as one continuous system: x = [p v phi delta_f], input the
/// applied delta_f command [rad/s].
/// @throws std::invalid_argument if the model is not lateral3 (p v phi) with a delta_f input,
///         or the actuator's pole or gain is not positive.
StateSpace roll_plant_with_actuator(const StateSpace& lateral, const RollLoopConfig& config);

/// The loop broken at `where` (loop_margins.h conventions: closing it sets w = y).
/// @throws std::invalid_argument as roll_plant_with_actuator, or for a rate, cut-off (not in
///         (0, rate/2)), latency or gain out of range.
BrokenLoop roll_broken_loop(const StateSpace& lateral, const RollLoopConfig& config, LoopBreak where);

/// The closed loop driven by the roll set-point r through the reference generator.
struct SetpointLoop {
  Eigen::MatrixXd A;               ///< transition over one control period
  Eigen::VectorXd B;               ///< set-point input
  Eigen::RowVectorXd phi;          ///< output: the aircraft's roll angle [rad]
  Eigen::RowVectorXd phi_ref;      ///< output: the reference angle the controller uses [rad]
  Eigen::RowVectorXd p;            ///< output: the roll rate [rad/s]
  Eigen::RowVectorXd delta_f_cmd;  ///< output: the actuator command [rad/s]
  double dt_s = 0.0;
};

/// @throws std::invalid_argument as roll_broken_loop.
SetpointLoop roll_setpoint_loop(const StateSpace& lateral, const RollLoopConfig& config);

/// A response of the set-point loop to a step of the set-point.
struct StepResponse {
  std::vector<double> t_s, phi_rad, phi_ref_rad, p_radps, delta_f_cmd_radps;
};

/// The response to a set-point step of `step_rad` from rest, over `duration_s`.
StepResponse roll_step_response(const SetpointLoop& loop, double step_rad, double duration_s);

/// What `rig loop` states of one model and gain set.
struct RollLoopAnalysis {
  LoopMargins margins;          ///< broken where asked
  std::vector<LoopPole> poles;  ///< of the feedback loop (the generator's are not in it)
  int poles_at_origin = 0;      ///< pure delays
  bool has_dominant_pair = false;
  /// The least-damped complex pair (Im > 0): the oscillation a step or a disturbance shows.
  LoopPole dominant;
  double bandwidth_hz = 0.0;           ///< -3 dB of phi / phi_ref (from its value at 0 Hz)
  double setpoint_bandwidth_hz = 0.0;  ///< -3 dB of phi / the set-point, through the generator
  double dc_gain = 0.0;                ///< phi / phi_ref at 0 Hz [-]
  double saturation_error_rad = 0.0;   ///< an angle error that alone saturates the command: 1 / kp
};

/// Analyses the loop broken at `where`; `full` false: the margins only (no poles, bandwidth).
/// @throws std::invalid_argument as roll_broken_loop.
RollLoopAnalysis analyse_roll_loop(const StateSpace& lateral, const RollLoopConfig& config,
                                   LoopBreak where = LoopBreak::kActuator, const MarginOptions& options = {},
                                   bool full = true);

/// Frequency responses for plots, on `omega_radps`: the return ratio L and phi / phi_ref.
struct RollLoopResponse {
  std::vector<double> omega_radps;
  std::vector<std::complex<double>> ratio;     ///< L
  std::vector<std::complex<double>> tracking;  ///< phi / phi_ref
};
RollLoopResponse roll_loop_response(const StateSpace& lateral, const RollLoopConfig& config, LoopBreak where,
                                    const std::vector<double>& omega_radps);

/// A design request: the phase margin at the crossover.
struct DesignRequest {
  double phase_margin_deg = 45.0;
  double crossover_hz = 2.0;
  /// The design must track: phi/phi_ref at 0 Hz at least this [-], i.e. a steady roll error
  /// at most half the reference. The thesis gains reach 0.77 (slow) and 0.88 (fast) on set 1; a
  /// PD with kp near 0 reaches any phase margin and holds no angle.
  double min_dc_gain = 0.5;
};

/// A designed gain set.
struct RollDesign {
  bool feasible = false;
  GainSet gains;
  double lowpass_cutoff_hz = 15.0;  ///< the cut-off it needs (the given one if that is enough)
  RollLoopAnalysis analysis;        ///< of the loop with the designed gains and cut-off
  std::string note;                 ///< why not feasible, or what was changed
};

/// PD gains with which L(crossover) = exp(j (-180 deg + phase margin)) on the loop broken at
/// the actuator: L is linear in (kp, kd), so they solve two real equations. Feasible if both
/// gains are >= 0, the closed loop is stable, the crossover asked for is the loop's critical
/// one (the reached phase margin within 1 deg of the request) and phi/phi_ref at 0 Hz is at
/// least min_dc_gain. If not, the cut-off of the low-pass is raised (20, 25, 30, 40, 50, 64 Hz,
/// up to rate / 8) until it is; if none is, the note says why and at which crossovers from 0.1
/// to 10 Hz the request is met with the configured cut-off.
/// @throws std::invalid_argument for a request out of range (margin in (0, 90) deg, crossover
///         in (0, rate / 4) Hz) or as roll_broken_loop.
RollDesign design_roll_gains(const StateSpace& lateral, const RollLoopConfig& config, const DesignRequest& request);

}  // namespace nimble
