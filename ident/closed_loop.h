#pragma once
/// Closed-loop validation (thesis Section 9.3, Tables 9-11): the model flown by a copy of
/// the attitude controller and the flap actuator, driven by the logged roll set-point and
/// throttle, from the measured initial state; the simulated states and delta_f are compared
/// with the measured ones. An unstable model that is only held by the controller is judged
/// the way it is used.

#include <map>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "controller/attitude_controller.h"
#include "core/model.h"
#include "core/vehicle.h"
#include "ident/flight_data.h"
#include "ident/metrics.h"
#include "ident/signal.h"

namespace nimble::ident {

struct ClosedLoopOptions {
  ControllerConfig controller;                          ///< the controller copy (rate = data grid rate)
  std::string gain_set = "fast";                        ///< roll gain set flown
  double flap_gain_per_s = 8.97;                        ///< flap actuator numerator (thesis Eq 33) [1/s]
  double flap_pole_radps = 12.56;                       ///< flap actuator pole (thesis Eq 33) [rad/s]
  Interpolation interpolation = Interpolation::kCubic;  ///< resampling onto the controller's rate
};

struct ClosedLoopResult {
  std::string source;
  std::string model;  ///< name of the model flown
  std::string gain_set;
  double rate_hz = 0.0;
  Eigen::VectorXd t_s;
  /// Measured and simulated p [rad/s], v [m/s], phi [rad], delta_f [rad/s].
  std::map<std::string, Eigen::VectorXd> measured, simulated;
  Eigen::VectorXd phi_sp;   ///< roll set-point flown [rad]
  Eigen::VectorXd phi_ref;  ///< the controller copy's roll reference (reference generator output) [rad]
  /// Fit of each simulated signal against the measured one (P = 1: nothing fitted).
  std::map<std::string, FitMetrics> fits;
};

/// Simulates `model` (lateral3, or blackbox3 with its own phi-dot row; delta_f, optionally delta_t) in closed loop on the
/// data's phi_sp and delta_t, at the controller's rate. The model's effects (section
/// effects:, as rig discrepancy writes them) fly too: extra moment and force from the simulated
/// p, v, phi, delta_f and the measured u, w, delta_d, r they need.
/// @throws DataError if the data lacks p, v, phi, delta_f or phi_sp, or a channel an effect needs;
///         std::invalid_argument if the model does not fit or the gain set is unknown.
ClosedLoopResult validate_closed_loop(const FlightData& data, const DerivativeModel& model, const Vehicle& vehicle,
                                      const ClosedLoopOptions& options);

/// Writes closed_loop.png into `dir` (with its .dat data and .gp script): the time histories of
/// p, phi (with phi_sp and the simulated phi_ref), v and delta_f, measured against simulated, each
/// panel titled with its r_xy, R^2 and RMSE; and autocorrelation.png: the residual
/// autocorrelation of each of them with the 95 % bounds (thesis Figs C.4-C.9). Returns the PNG paths.
/// @throws std::runtime_error if gnuplot (Debian package gnuplot-nox) is missing or fails.
std::vector<std::string> plot_closed_loop(const ClosedLoopResult& result, const std::string& dir);

/// The closed-loop validation as `rig validate --closed-loop --json` reports it: source, model,
/// gain set, rate, samples and each of p, v, phi, delta_f's fit; `plots` recorded when not empty.
std::string closed_loop_json(const ClosedLoopResult& result, const std::vector<std::string>& plots);

/// The controller configuration the closed-loop copies fly unless told otherwise:
/// rig_configs/controller/nimble_attitude.yaml of the source tree this library was built from.
std::string default_controller_file();

}  // namespace nimble::ident
