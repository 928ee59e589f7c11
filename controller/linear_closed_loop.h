#pragma once
/// Closed-loop simulation of the attitude controller on a linear lateral model:
/// the harness used to calibrate roll_cmd_to_delta_f_radps and to test that
/// both gain sets fly the manoeuvres stably. Not part of the live rig.
///
/// Loop: plant x = [p v phi] of a lateral3 model (inputs delta_f and optionally
/// delta_t), exact ZOH at plant_rate_hz (default 1 kHz); flap actuator
/// delta_f = flap_gain / (s + flap_pole) * delta_f_cmd (thesis Eq 33: 8.97/(s+12.56)),
/// exact at the plant rate (its output held over each plant step); controller at
/// its own rate (512 Hz) reading the true p and phi (theta = q = 0), its commands
/// held between its steps.

#include <string>
#include <vector>

#include "contract/default_rates.h"
#include "controller/attitude_controller.h"
#include "controller/manoeuvre.h"
#include "core/model.h"
#include "core/vehicle.h"

namespace nimble {

/// Options of the linear closed-loop simulation.
struct LinearLoopOptions {
  double plant_rate_hz = contract::kDefaultPlantRateHz;  ///< plant integration rate [Hz]
  double flap_gain_per_s = 8.97;                         ///< numerator of the flap actuator [1/s] (thesis Eq 33)
  double flap_pole_radps = 12.56;                        ///< pole of the flap actuator [rad/s] (thesis Eq 33)
  double tail_s = 4.0;                                   ///< hover simulated after the manoeuvre ends [s]
  double settle_window_s = 0.5;                          ///< final window checked for the return to hover [s]
  bool record_trace = false;                             ///< keep every plant sample in LinearLoopResult::trace
};

/// One plant sample of the simulation.
struct LinearLoopSample {
  double t_s;                ///< time since the manoeuvre start [s]
  double p_radps;            ///< roll rate [rad/s]
  double v_mps;              ///< side velocity [m/s]
  double phi_rad;            ///< roll angle [rad]
  double delta_f_radps;      ///< actuator output [rad/s]
  double delta_f_cmd_radps;  ///< controller command [rad/s]
  double delta_t_pct;        ///< throttle deviation fed to the model [%]
  double roll_sp_rad;        ///< roll set-point [rad]
  double roll_ref_rad;       ///< roll reference [rad]
  double roll_cmd_norm;      ///< normalised roll command [-]
};

/// Range (max - min) of a signal.
struct SignalRange {
  double min = 0.0;
  double max = 0.0;
  /// max - min
  double range() const { return max - min; }
};

/// Outcome of one simulation.
struct LinearLoopResult {
  SignalRange p_radps, v_mps, phi_rad;  ///< over the whole run
  SignalRange delta_f_radps;            ///< actuator output over the whole run
  SignalRange delta_f_cmd_radps;        ///< controller command over the whole run
  double settle_max_abs_p_radps = 0.0;  ///< max |p| in the final settle window
  double settle_max_abs_v_mps = 0.0;    ///< max |v| in the final settle window
  double settle_max_abs_phi_rad = 0.0;  ///< max |phi| in the final settle window
  double duration_s = 0.0;              ///< simulated time [s]
  bool finite = true;                   ///< no state became non-finite or absurdly large
  ControllerCounters counters;          ///< controller counters at the end
  std::vector<LinearLoopSample> trace;  ///< every plant sample if requested
};

/// Reference ranges (max - min) a calibration aims at.
struct TargetRanges {
  double p_radps = 12.06;        ///< thesis Table 9.4, identification data set 1
  double v_mps = 1.17;           ///< thesis Table 9.4, identification data set 1
  double phi_rad = 0.89;         ///< thesis Table 9.4, identification data set 1
  double delta_f_radps = 115.0;  ///< thesis Table 9.10: RMSE 12.59 rad/s = 10.95 % of the measured range
};

/// Calibration score: root mean square of log(range / target) over p, v, phi and
/// the actuator delta_f [-]; 0 is a perfect match, 0.69 a factor 2 on average.
/// Infinite if the run diverged or a range is zero.
double range_score(const LinearLoopResult& result, const TargetRanges& target = {});

/// True if the run stayed finite and its final settle window is back at hover:
/// |phi| < phi_tol_rad, |p| < p_tol_radps, |v| < v_tol_mps.
bool returned_to_hover(const LinearLoopResult& result, double phi_tol_rad = 0.01, double p_tol_radps = 0.1,
                       double v_tol_mps = 0.05);

/// Flies `player` from rest with `controller_config` using roll gain set
/// `gain_set` on the linear model.
/// @throws std::invalid_argument if the model is not lateral3 or lacks delta_f,
///         the gain set is unknown, or an option is not positive.
LinearLoopResult simulate_linear_closed_loop(const DerivativeModel& model, const Vehicle& vehicle,
                                             const ControllerConfig& controller_config, const std::string& gain_set,
                                             const ManoeuvrePlayer& player, const LinearLoopOptions& options = {});

}  // namespace nimble
