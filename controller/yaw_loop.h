#pragma once
/// Linear analysis of the roll and yaw loops together on a four-state lateral model (thesis
/// Table 8.3, states p r v phi): the harness used to calibrate the yaw gains
/// (calibrate_yaw_gains) and to test them. Not part of the live rig.
///
/// Loop (regulation about the model's trim, references zero, no saturation, continuous time):
///   plant      x = [p r v phi] of a lateral4 model, inputs delta_f [rad/s] and delta_w [rad]
///              psi_dot = r cos(phi0) / cos(theta0)
///   roll       cmd_r = LP(-(kp phi + kd p)),   delta_f_cmd = roll_cmd_to_delta_f_radps cmd_r
///              delta_f = flap_gain / (s + flap_pole) delta_f_cmd              (thesis Eq 33)
///   yaw        cmd_y = LP(-(kp_psi psi + kd_psi r)), wing_root_cmd = yaw_cmd_to_wing_root_rad cmd_y
///              delta_w = wn2 / (s^2 + c1 s + wn2) wing_root_cmd               (plant servo)
/// LP is the second-order Butterworth at the axis's cut-off. State of the closed loop:
/// [p r v phi psi delta_f delta_w delta_w_rate lp_roll lp_roll_rate lp_yaw lp_yaw_rate].
///
/// The controller is the onboard one at 512 Hz; its sampling is left out here: at the gains
/// the calibration considers, the loops' poles stay below a tenth of the Nyquist frequency.

#include <complex>
#include <vector>

#include <Eigen/Dense>

#include "controller/attitude_controller.h"
#include "core/model.h"

namespace nimble {

/// Parameters of the linear roll-yaw loop that are not the yaw gains.
struct YawLoopOptions {
  GainSet roll_gains{1.406, 0.200};          ///< roll PD (default: the fast set)
  double roll_cmd_to_delta_f_radps = 125.0;  ///< roll map [rad/s per unit command]
  double yaw_cmd_to_wing_root_rad = -0.35;   ///< yaw map [rad per unit command]
  double lowpass_cutoff_hz = 15.0;           ///< both command low-passes [Hz]
  double flap_gain_per_s = 8.97;             ///< thesis Eq 33
  double flap_pole_radps = 12.56;            ///< thesis Eq 33
  double servo_wn2_rad2ps2 = 554.2;          ///< plant servo wn^2
  double servo_c1_radps = 30.25;             ///< plant servo 2 zeta wn
};

/// Options with the controller's roll gain set `gain_set`, maps and cut-offs.
YawLoopOptions yaw_loop_options(const ControllerConfig& config, const std::string& gain_set);

/// Closed-loop matrix A_cl (x_dot = A_cl x) of the roll and yaw loops on `lat4`.
/// @throws std::invalid_argument if `lat4` is not p r v phi with inputs delta_f and delta_w,
///         or an option is not positive where it must be.
Eigen::MatrixXd yaw_closed_loop_matrix(const StateSpace& lat4, const GainSet& yaw_gains, const YawLoopOptions& options);

/// Closed-loop poles of one yaw gain pair.
struct YawLoopPoles {
  std::vector<std::complex<double>> poles_s;  ///< [1/s], sorted by real part
  double max_real_per_s = 0.0;                ///< largest real part [1/s]
  bool stable = false;                        ///< every pole strictly in the left half plane
  double min_damping = 1.0;                   ///< smallest damping ratio of the complex poles [-]
};

YawLoopPoles analyse_yaw_loop(const StateSpace& lat4, const GainSet& yaw_gains, const YawLoopOptions& options);

}  // namespace nimble
