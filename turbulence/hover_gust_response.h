#pragma once
/// The rig's hover in Dryden side gusts as a linear system, and the comparison of a flown
/// record with it (rig turbulence-response, tests/system/test_turbulence_rig.cc).
///
/// Closed-loop linear model (continuous, 8 states):
///   aircraft  [p v phi]: the lateral3 model (core/model.h build_state_space, with delta_t = 0);
///             the gust enters where the aerodynamics see v - v_g, i.e. as the input -v_g on
///             A's v column (Lv Izz/Ic in p_dot, Yv/m in v_dot);
///   actuator  delta_f_dot = -pole delta_f + gain delta_f_cmd (thesis Eq 33: 8.97/(s+12.56));
///   controller roll_cmd = LP( -(Kp phi + Kd p) ) (hover: the references are 0), LP the
///             second-order Butterworth wc^2/(s^2 + sqrt(2) wc s + wc^2) at the controller's
///             cut-off, delta_f_cmd = roll_cmd_to_delta_f_radps roll_cmd;
///   gust      the plant's Dryden filter (turbulence/dryden.h time_based_second_order with the
///             plant's sigma and time scale), driven by unit-intensity white noise w.
/// Left out, hence the bandwidth below which the comparison holds: the controller's 512 Hz
/// sampling and hold, the transport delay between plant and controller (a few ms in
/// lockstep), the saturations and the |roll_cmd| term of the mixing (both nonlinear, inert for
/// small gusts), sin(phi) against phi. Each is below a few degrees of phase under 10 Hz, where
/// the loop gain is already small; on a flight on the truth the model holds to 20 Hz and beyond.
/// Flying on the estimate (run.controller_input estimate) adds the estimator's noise and lag,
/// which the model does not have: p and phi then carry 3-8 times the model's power above 1 Hz.
///
/// Comparison: Welch PSDs (spectral_estimates.h) of the flown p, v, phi against the expected
/// Welch estimate of the model's sampled output (welch_expectation(): the analytical PSD with
/// the window's leakage and the aliasing, which differ from the analytical PSD where it curves
/// within a bin: up to 16 % at the lowest bins of v with 8.2 s segments), with the chi-square confidence band of the
/// Welch bins (uncertainty.h). Over the bins from 2 (bin 1 carries the removal of the record
/// mean) to f_max: (1) of every other bin (nearly independent), at most
/// binomial_upper_quantile(n, 1 - level, 1 - false_alarm) outside the band; (2) the mean
/// of estimate / expectation over all bins within 3 standard deviations of 1 (standard
/// deviation from the bins' degrees of freedom and the Hann correlation of neighbouring bins,
/// rho_1 = 4/9, rho_2 = 1/36). Variances: the flight's sample variance against the model's
/// Lyapunov variance, within 3 times its standard deviation (uncertainty.h, from the model's
/// sampled autocovariance over the record length).

#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "core/model.h"
#include "core/vehicle.h"
#include "turbulence/linear_system.h"

namespace nimble::turbulence {

/// Parameters of the hover closed loop besides the aircraft model.
struct HoverLoopParameters {
  double kp_per_rad = 1.406;                 ///< roll P gain (controller gain set) [1/rad]
  double kd_per_radps = 0.200;               ///< roll D gain [s/rad]
  double lowpass_cutoff_hz = 15.0;           ///< Butterworth cut-off of the roll command [Hz]
  double roll_cmd_to_delta_f_radps = 125.0;  ///< delta_f_cmd per unit roll command [rad/s]
  double flap_gain_per_s = 8.97;             ///< flap actuator numerator [1/s]
  double flap_pole_radps = 12.56;            ///< flap actuator pole [rad/s]
  double gust_sigma_mps = 0.1;               ///< Dryden sigma [m/s], > 0
  double gust_time_scale_s = 1.0;            ///< Dryden time scale T [s], > 0
};

/// The closed loop: states [p, v, phi, delta_f, lp, lp_dot, gust_1, gust_2], input "w"
/// (unit-intensity white noise), outputs p [rad/s], v [m/s], phi [rad], v_g [m/s],
/// delta_f [rad/s].
/// @throws std::invalid_argument if the model is not lateral3 with a delta_f input, or a
///         parameter is not positive (gains may be 0).
LinearSystem hover_gust_loop(const DerivativeModel& model, const Vehicle& vehicle, const HoverLoopParameters& params);

/// Settings of the comparison.
struct ResponseComparisonOptions {
  double f_max_hz = 10.0;         ///< compare the bins up to this frequency [Hz]
  std::size_t welch_segment = 0;  ///< M [samples], a power of two; 0: default_welch_segment()
  double level = 0.95;            ///< coverage of the confidence band
  double false_alarm = 1e-3;      ///< false-alarm rate of the bin count, per output
};

/// One output's comparison.
struct OutputComparison {
  std::string name;                       ///< p, v, phi
  std::string unit;                       ///< rad/s, m/s, rad
  Eigen::VectorXd omega_radps;            ///< Welch bins 1 .. (up to Nyquist)
  Eigen::VectorXd welch;                  ///< flight's Welch PSD [unit^2/(rad/s)]
  Eigen::VectorXd expected;               ///< model's expected Welch estimate
  Eigen::VectorXd analytical;             ///< model's analytical PSD
  Eigen::VectorXd lower, upper;           ///< confidence band around `expected`
  std::size_t bins = 0;                   ///< bins compared: 2 .. f_max (bin 1 carries the mean removal)
  std::size_t counted = 0;                ///< every other of them: the nearly independent bins counted
  std::size_t outside = 0;                ///< of the counted, outside the band
  std::size_t allowed = 0;                ///< binomial bound on `outside`
  double mean_ratio = 0.0;                ///< mean welch / expected over the bins up to f_max
  double mean_ratio_sigma = 0.0;          ///< its standard deviation under the model
  double max_analytical_deviation = 0.0;  ///< max |expected / analytical - 1| up to f_max
  double model_variance = 0.0;            ///< Lyapunov [unit^2]
  double flight_variance = 0.0;           ///< sample variance of the record [unit^2]
  double flight_variance_sigma = 0.0;     ///< its standard deviation under the model [unit^2]
  bool bins_agree = false;                ///< outside <= allowed
  bool mean_agrees = false;               ///< |mean_ratio - 1| <= 3 mean_ratio_sigma
  bool variance_agrees = false;           ///< |flight - model| <= 3 flight_variance_sigma
};

/// The whole comparison.
struct ResponseComparison {
  double dt_s = 0.0;
  std::size_t samples = 0;
  std::size_t segment_length = 0, segments = 0;
  double dof = 0.0;
  double band_lower = 0.0, band_upper = 0.0;  ///< multipliers of the band
  double f_max_hz = 0.0;
  double level = 0.0;
  std::vector<OutputComparison> outputs;  ///< p, v, phi
  /// True if every output agrees in both spectral checks and its variance.
  bool agrees() const;
};

/// Compares records of p, v, phi (keys "p", "v", "phi"; equal length, sampled every dt_s,
/// stationary: the caller drops the start-up) with `loop` (hover_gust_loop()).
/// @throws std::invalid_argument if a record is missing or too short for the segment, or the
///         options are out of range (f_max must lie below the Nyquist frequency).
ResponseComparison compare_hover_response(const LinearSystem& loop,
                                          const std::map<std::string, Eigen::VectorXd>& records, double dt_s,
                                          const ResponseComparisonOptions& options = {});

}  // namespace nimble::turbulence
