#pragma once
/// Linear analysis of the pitch loop on a longitudinal model: the harness used to
/// calibrate the pitch PD gains (calibrate_pitch_gains) and to test them. Not part
/// of the live rig.
///
/// Loop (regulation about the model's trim, references zero, no saturation):
///   plant      x = [q u w theta] of a longitudinal model, input delta_d (dihedral) [rad]
///   servo      delta_d = wn2 / (s^2 + c1 s + wn2) * dihedral_cmd   (plant config `servo`)
///   controller pd  = -(kp theta + kd q)                               [-]
///              cmd = LP(pd)  (second-order Butterworth at the pitch cut-off)
///              dihedral_cmd = pitch_cmd_to_dihedral_rad * cmd         [rad]
///
/// Two forms:
///  - discrete (default): the controller at rate_hz with the exact difference
///    equation of SecondOrderLowPass (Tustin, pre-warped), its command held over
///    each control period (zero-order hold) on the plant + servo, discretised
///    exactly (matrix exponential); optionally delayed by whole control periods.
///    Closed-loop poles z are reported as s = ln(z) * rate_hz.
///  - continuous: the same loop with the analogue Butterworth and a continuous PD.
///
/// Damping ratio of a pole s: zeta = -Re(s) / |s|. "Oscillatory" poles are those
/// with a non-zero imaginary part; real poles (e.g. the slow speed pole of the
/// closed loop) do not count for the smallest damping.

#include <complex>
#include <cstddef>
#include <optional>
#include <vector>

#include <Eigen/Dense>

#include "contract/rates.h"
#include "controller/attitude_controller.h"
#include "core/model.h"

namespace nimble {

/// Parameters of the linear pitch loop that are not the PD gains.
struct PitchLoopOptions {
  double rate_hz = contract::kDefaultControlRateHz;  ///< controller rate [Hz]
  double lowpass_cutoff_hz = 15.0;                   ///< pitch command low-pass cut-off [Hz]
  double pitch_cmd_to_dihedral_rad = 0.35;           ///< dihedral per unit pitch command [rad]
  double servo_wn2_rad2ps2 = 554.2;                  ///< servo wn^2 [rad^2/s^2] (plant config servo.wn2_rad2ps2)
  double servo_c1_radps = 30.25;                     ///< servo damping term [rad/s] (plant config servo.c1_radps)
  bool continuous = false;                           ///< analogue loop instead of the 512 Hz discrete one
  int delay_steps = 0;                               ///< whole control periods of command delay (discrete only)
};

/// Options with the rate, pitch cut-off and dihedral map of `config` (servo: defaults).
PitchLoopOptions pitch_loop_options(const ControllerConfig& config);

/// Plant and servo as one continuous model: x = [q u w theta delta_d delta_d_rate],
/// input the dihedral command [rad].
/// @throws std::invalid_argument if `lon` does not have the longitudinal states
///         q u w theta or no delta_d input, or the servo parameters are not positive.
StateSpace pitch_plant_with_servo(const StateSpace& lon, const PitchLoopOptions& options);

/// Closed-loop matrix: continuous A_cl (xdot = A_cl x) if options.continuous,
/// else the transition matrix Phi_cl (x[k+1] = Phi_cl x[k]) over one control period.
/// State: the 6 plant + servo states, then the 2 low-pass states (discrete: the
/// transposed direct-form states of SecondOrderLowPass; continuous: output and its
/// rate), then delay_steps held commands (discrete only).
/// @throws std::invalid_argument as pitch_plant_with_servo, or for a bad rate,
///         cut-off (not in (0, rate/2)), negative gains, map or delay.
Eigen::MatrixXd pitch_closed_loop_matrix(const StateSpace& lon, const GainSet& gains, const PitchLoopOptions& options);

/// Closed-loop poles of one gain pair.
struct PitchLoopPoles {
  std::vector<std::complex<double>> poles_s;  ///< continuous(-equivalent) poles [1/s], sorted by real part
  double max_real_per_s = 0.0;                ///< largest real part [1/s]
  bool stable = false;                        ///< every pole strictly in the left half plane (|z| < 1)
  bool has_oscillatory = false;               ///< at least one complex pair
  double min_damping = 0.0;                   ///< smallest damping ratio of the complex poles [-]
  std::complex<double> least_damped{};        ///< the complex pole with that damping (positive imaginary part)
};

/// Poles of the closed loop of `lon` with the pitch gains `gains`.
/// @throws std::invalid_argument as pitch_closed_loop_matrix.
PitchLoopPoles analyse_pitch_loop(const StateSpace& lon, const GainSet& gains, const PitchLoopOptions& options);

/// One point of a gain scan.
struct PitchGainPoint {
  GainSet gains;
  PitchLoopPoles poles;
};

/// Every point of a kp x kd grid and the best one.
struct PitchGainScan {
  std::vector<PitchGainPoint> points;  ///< kp-major: points[i * kd.size() + j] = (kp[i], kd[j])
  /// Index of the stable point with oscillatory poles whose smallest damping is
  /// largest (ties: the first); none if no point is stable.
  std::optional<std::size_t> best;
};

/// Scans the grid kp_values x kd_values.
/// @throws std::invalid_argument as pitch_closed_loop_matrix, or for an empty grid.
PitchGainScan scan_pitch_gains(const StateSpace& lon, const PitchLoopOptions& options,
                               const std::vector<double>& kp_values, const std::vector<double>& kd_values);

/// Default grid of calibrate_pitch_gains: kp 0.005..0.300 step 0.005 [1/rad].
std::vector<double> default_pitch_kp_grid();
/// Default grid of calibrate_pitch_gains: kd 0.0005..0.0400 step 0.0005 [s/rad].
std::vector<double> default_pitch_kd_grid();

}  // namespace nimble
