#pragma once
/// Identification of the lateral body dynamics from flight data (thesis
/// Section IV, Appendix C): processing, the regression equations of the
/// lateral3 and lateral4 structures, dimensional derivatives, metrics,
/// residual whiteness, state PSDs of hover and manoeuvre, and the modes of the
/// identified model.
///
/// Equations (dimensional derivatives come out directly):
///   lateral3:  Ic/Izz * p_dot      = Lp p + Lv v + sum_u L_u u
///              m * v_dot_star      = Yp p + Yv v + sum_u Y_u u
///   lateral4 (decoupled L and N, thesis Eq 8.7 / C.11):
///              Ic/Izz * p_dot      = Lp p + Lr r + Lv v + sum_u L_u u
///              Ic/Ixx * r_dot      = Np p + Nr r + Nv v + sum_u N_u u
///              m * v_dot_star      = Yp p + Yr r + Yv v + sum_u Y_u u
/// with v_dot_star = v_dot - w0 p - g cos(theta0) cos(phi0) phi (Eq 21), and
/// + u0 r in lateral4 (Eq C.10). Inputs u in {delta_f, delta_t, delta_d, delta_w}.

#include <complex>
#include <cstddef>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "core/model.h"
#include "core/modes.h"
#include "core/vehicle.h"
#include "ident/flight_data.h"
#include "ident/metrics.h"
#include "ident/output_error.h"
#include "ident/regression.h"
#include "ident/signal.h"
#include "ident/spectrum.h"

namespace nimble::ident {

/// A time interval [start_s, end_s] of a record.
struct TimeRange {
  double start_s = 0.0;
  double end_s = 0.0;
};

/// How hover and manoeuvre parts of a record are chosen.
///  - Explicit: `hover` and/or `manoeuvre` ranges given.
///  - Otherwise, with a phi_sp channel: a sample is active when
///    |phi_sp| > active_threshold_rad; active samples are widened by margin_s
///    on both sides; the widened runs are the manoeuvre, the rest hover;
///    runs shorter than min_length_s are dropped.
///  - Otherwise the whole record is the manoeuvre and there is no hover part.
struct SegmentOptions {
  std::vector<TimeRange> hover;
  std::vector<TimeRange> manoeuvre;
  double active_threshold_rad = 0.035;  ///< about 2 deg
  double margin_s = 1.0;
  double min_length_s = 1.0;
};

/// Hover and manoeuvre parts of a record.
struct Segments {
  std::vector<TimeRange> hover;
  std::vector<TimeRange> manoeuvre;
  std::string how;  ///< "time ranges", "|phi_sp| activity" or "whole record"
};

/// Hover and manoeuvre segments of uniform data (see SegmentOptions).
/// @throws std::invalid_argument for a range with end <= start.
Segments find_segments(const UniformData& data, const SegmentOptions& options);

/// Sample index ranges [first, last) of `ranges` on the grid of `data`.
std::vector<std::pair<Eigen::Index, Eigen::Index>> sample_ranges(const UniformData& data,
                                                                 const std::vector<TimeRange>& ranges);

/// A regressor added to an equation of a structure (e.g. {"Y", "v_abs_v"});
/// its parameter is named <equation>_<signal>. The signal must exist in the
/// prepared data (add it with IdentOptions::add_signals).
struct ExtraRegressor {
  std::string equation;
  std::string signal;
};

/// Options of identify().
struct IdentOptions {
  Structure structure = Structure::kLateral3;  ///< lateral3 or lateral4
  Method method = Method::kWls;
  /// Inputs; empty: delta_f, delta_t, and delta_d, delta_w when the data has them.
  std::vector<std::string> inputs;
  Trim trim;  ///< u0 [m/s] (lateral4 only), w0 [m/s], theta0, phi0 [rad] of Eq 21 / C.10
  ProcessingOptions processing;
  double wls_window_s = 2.0;       ///< WLS residual-covariance window [s], > 0
  bool wls_cross_equation = true;  ///< see WlsOptions
  double correlation_threshold = 0.9;
  /// Bartlett lags of the coloured-residual covariance [samples]; 0:
  /// 4 rate / (2 cutoff), four correlation times of band-limited residuals.
  std::size_t coloured_lags = 0;
  std::size_t whiteness_lags = 50;
  std::size_t whiteness_lag_step = 0;  ///< samples per lag; 0: round(rate / (2 cutoff))
  double psd_segment_s = 2.0;          ///< Welch segment length [s]
  SegmentOptions segments;
  std::string model_name;  ///< name of the identified model; empty: from the source
  /// Called with the prepared (filtered) signals before the regression, to
  /// add signals for extra regressors.
  std::function<void(UniformData&)> add_signals;
  std::vector<ExtraRegressor> extra_regressors;
  /// Generic terms (a model file's terms:, core/terms.h), fitted alongside the derivatives: each
  /// adds the column of its expression, evaluated along the filtered record at its sample time
  /// (evaluate_along()), to its equation; its coefficient is the parameter "<equation>:<expression>"
  /// (term_parameter_name()) and the identified model carries the terms with the fitted values.
  std::vector<Term> terms;
  /// Method::kOutputError's options (ident/output_error.h).
  OutputErrorOptions output_error;
};

/// Data prepared for regression.
struct PreparedData {
  UniformData raw;       ///< resampled, not filtered (PSDs)
  UniformData filtered;  ///< resampled and filtered, plus "<state>_dot" of every state and "v_dot_star"
};

/// Resamples and filters `data` and adds the state derivatives of `structure`
/// and v_dot_star from `trim` and `gravity_mps2`.
/// @throws DataError if a channel the structure needs is missing; as process().
PreparedData prepare(const FlightData& data, Structure structure, const Trim& trim, double gravity_mps2,
                     const ProcessingOptions& options);

/// Inputs used when IdentOptions::inputs is empty: delta_f and delta_t, and delta_d, delta_w
/// when the data has them and they are excited (input_excited()). Each input left out is
/// described in `left_out` (if given).
std::vector<std::string> default_inputs(const FlightData& data, std::vector<std::string>* left_out = nullptr);

/// Excitation floor of the optional servo inputs [rad]: 10 steps of the actuator interface's
/// resolution (1e-4 rad, plant.command_resolution.servo_rad and the CAN frames). An input that
/// moves less than this (standard deviation over the record) is at the size of its own
/// quantisation, and its derivatives cannot be estimated: a rig flight whose dihedral moved
/// 2.6e-4 rad gave L_dd with sigma_c 146 %.
constexpr double kServoExcitationFloorRad = 1e-3;

/// True if channel `name` of `data` varies by at least its excitation floor (standard deviation
/// over the record; kServoExcitationFloorRad for delta_d and delta_w; any variation otherwise).
bool input_excited(const FlightData& data, const std::string& name, double* std_out = nullptr);

/// Name of the parameter of `regressor` in the equation `letter`: "Lp",
/// "Yv", "L_df" (inputs use their derivative suffix), otherwise
/// "<letter>_<regressor>".
std::string parameter_name(const std::string& letter, const std::string& regressor);

/// The regression equations of a lateral structure (see the file comment).
/// @throws std::invalid_argument for the longitudinal structure or an unknown input.
std::vector<Equation> lateral_equations(Structure structure, const std::vector<std::string>& inputs,
                                        const Vehicle& vehicle);

/// Name of a term's column in prepared data: "term:<expression>".
std::string term_signal_column(const Term& term);
/// Adds the column of `term` to `data` (its expression evaluated along the samples at the
/// data's sample time, stateful operators starting at the first sample; evaluate_along()).
/// @throws DataError if `data` lacks a signal the expression reads.
void add_term_column(UniformData& data, const Term& term);
/// The column add_term_column() adds, without adding it.
Eigen::VectorXd term_column(const UniformData& data, const Term& term);

/// A measured output and its estimate.
struct OutputFit {
  std::string output;  ///< e.g. "p_dot", "v_dot_star"
  std::string unit;    ///< e.g. "rad/s^2"
  Eigen::VectorXd measured;
  Eigen::VectorXd estimated;
  FitMetrics metrics;
  Whiteness whiteness;  ///< of measured - estimated
};

/// PSDs of one state in hover and in the manoeuvre (Welch, unfiltered data).
struct StatePsd {
  std::string state;
  std::string unit;
  bool has_hover = false;
  bool has_manoeuvre = false;
  Psd hover;
  Psd manoeuvre;
};

/// Everything rig identify reports.
struct IdentResult {
  std::string source;
  IdentOptions options;
  std::vector<std::string> inputs;
  std::vector<std::string> inputs_left_out;  ///< optional inputs not excited enough, with why
  Vehicle vehicle;
  PreparedData data;
  RegressionResult regression;
  /// Dimensional derivatives (and extra-regressor parameters) in equation order.
  std::vector<std::string> parameter_order;
  std::map<std::string, ParameterEstimate> parameters;
  std::vector<CorrelatedPair> correlated;
  std::vector<OutputFit> fits;
  /// The identified linear model (extra regressors are not part of it).
  DerivativeModel model;
  StateSpace state_space;
  std::vector<std::complex<double>> eigenvalues;
  std::vector<Mode> modes;
  Segments segments;
  std::vector<StatePsd> psd;
  /// Diagnostics skipped because the record is too short for them (whiteness, a state PSD), each
  /// saying how long a record or part it needs; the rest of the result stands.
  std::vector<std::string> notes;
};

/// Identifies the lateral model of `data`. `vehicle_file` is recorded in the
/// identified model.
/// @throws DataError for missing channels or too few samples (fewer than 10
///         data rows per parameter); std::invalid_argument for invalid options
///         or regressors that cannot be separated.
IdentResult identify(const FlightData& data, const Vehicle& vehicle, const std::string& vehicle_file,
                     const IdentOptions& options);

/// The vehicle rig identify uses without --vehicle: rig_configs/vehicles/nimble_no_wifi.yaml
/// of the source tree this library was built from (the thesis's airframe).
std::string default_vehicle_file();

/// Lag step of the whiteness test [samples] for `requested` (0: round(rate / (2 cutoff)),
/// 1 without a low-pass).
std::size_t whiteness_lag_step(std::size_t requested, const ProcessingOptions& processing);

/// Bartlett lags of the coloured-residual covariance for `requested` (0: 4 * whiteness_lag_step(0)).
std::size_t coloured_lags(std::size_t requested, const ProcessingOptions& processing);

/// Welch PSDs of `states` of `raw` in the hover and manoeuvre segments.
std::vector<StatePsd> state_psds(const UniformData& raw, const std::vector<std::string>& states,
                                 const Segments& segments, double segment_s);

}  // namespace nimble::ident
