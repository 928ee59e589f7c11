#pragma once
/// Signal processing of flight data before identification: resampling onto a
/// uniform grid, zero-phase Butterworth low-pass filtering and differentiation.
///
/// The processing chain of rig identify (ident/identify.h) is
///   resample_uniform -> filtfilt(butterworth_lowpass) on every channel
///   -> differentiate the filtered states.
/// Defaults (ProcessingOptions): cubic interpolation onto 512 Hz, order 10, cut-off 9 Hz
/// (thesis Section 8.1: all data upsampled to 512 Hz, then low-passed).

#include <complex>
#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "contract/default_rates.h"
#include "ident/flight_data.h"

namespace nimble::ident {

/// Signals sampled on one time grid, by name (channel names, and derived
/// signals such as "p_dot" or a custom regressor such as "v_abs_v").
using SignalTable = std::map<std::string, Eigen::VectorXd>;

/// Flight data on a uniform time grid.
struct UniformData {
  std::string source;
  double rate_hz = 0.0;
  Eigen::VectorXd t_s;
  SignalTable signals;

  /// Number of samples.
  Eigen::Index size() const { return t_s.size(); }
  /// True if signal `name` exists.
  bool has(const std::string& name) const { return signals.count(name) != 0; }
  /// Signal `name`; @throws std::out_of_range naming the signal and the source if absent.
  const Eigen::VectorXd& at(const std::string& name) const;
};

/// How resample_uniform() reconstructs a channel between its samples.
enum class Interpolation {
  /// Straight lines between samples. Upsampling a channel recorded at fs this way
  /// attenuates its content at f by about sinc^2(f / fs) on average: 0.8 % at 5 Hz for
  /// the 100 Hz actuator feedback, enough to bias the control derivatives by a few
  /// tenths of a percent (ident/README.md).
  kLinear,
  /// Piecewise cubic Hermite: at each sample the slope of the parabola through it and its
  /// two neighbours (Bessel slopes, valid for uneven spacing; Catmull-Rom for even
  /// spacing), at the ends the slope of the parabola through the first (last) three
  /// samples. Exact for quadratics, continuous slope, local (four samples per interval).
  /// Gain about 1 - (w h)^4 / 80 (1.2e-4 low at 5 Hz from 100 Hz samples, against 8.2e-3
  /// for linear). A step overshoots by at most 7.4 % of its height, in the two intervals
  /// next to it; set-points (is_set_point()), which are steps, are therefore always
  /// interpolated linearly.
  kCubic,
};

/// True for channels that are set-points (phi_sp): step signals, resampled linearly.
bool is_set_point(const std::string& channel);

/// "linear" or "cubic".
std::string to_string(Interpolation interpolation);

/// Interpolation from "linear" or "cubic"; @throws std::invalid_argument otherwise.
Interpolation interpolation_from_string(const std::string& name);

/// Every channel interpolated onto t0 + k / rate_hz, where t0 is the latest first time
/// stamp of the channels and the grid ends at or before the earliest last time stamp.
/// Samples on the grid are kept exactly by both interpolations. Set-points are always linear.
/// @throws std::invalid_argument if rate_hz is not positive and finite, the
///         data has no channel, or the channels share less than two grid points;
///         DataError (ident/flight_data.h) from validate_flight_data.
UniformData resample_uniform(const FlightData& data, double rate_hz,
                             Interpolation interpolation = Interpolation::kCubic);

/// One second-order section b(z)/a(z) with a0 = 1:
/// H(z) = (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2).
/// A first-order section has b2 = a2 = 0.
struct SecondOrderSection {
  double b0 = 1.0, b1 = 0.0, b2 = 0.0;
  double a1 = 0.0, a2 = 0.0;
};

/// Digital Butterworth low-pass of `order` as cascaded second-order sections
/// (a first-order section last for an odd order), from the analog prototype by
/// the bilinear transform with the cut-off pre-warped, so that the digital
/// response is exactly -3 dB at cutoff_hz. Unity gain at DC.
/// @throws std::invalid_argument unless 1 <= order <= 40 and 0 < cutoff_hz < rate_hz / 2.
std::vector<SecondOrderSection> butterworth_lowpass(int order, double cutoff_hz, double rate_hz);

/// Complex frequency response of the cascade at f_hz.
std::complex<double> frequency_response(const std::vector<SecondOrderSection>& sos, double f_hz, double rate_hz);

/// Analytic squared magnitude of that digital Butterworth filter:
/// |H|^2 = 1 / (1 + (tan(pi f / fs) / tan(pi fc / fs))^(2 order)).
/// Applied forward and backward (filtfilt) the magnitude response is this |H|^2.
double butterworth_magnitude_squared(int order, double cutoff_hz, double rate_hz, double f_hz);

/// Causal filtering through the cascade (direct form II transposed). With
/// `steady_start` the section states start as if the input had always been x[0].
Eigen::VectorXd sosfilt(const std::vector<SecondOrderSection>& sos, const Eigen::VectorXd& x, bool steady_start);

/// Default edge padding of filtfilt [samples]: six periods of the cut-off
/// frequency, ceil(6 rate / cutoff) (342 samples at 512 Hz and 9 Hz), long
/// enough for the start transient of an order-10 filter to decay.
std::size_t default_padding(double cutoff_hz, double rate_hz);

/// Zero-phase filtering: forward then backward through the cascade, so the
/// magnitude response is |H|^2 and the phase is zero. Edges: the signal is
/// extended at both ends by `padding` samples of odd reflection about its end
/// values (2 x[0] - x[k], as MATLAB/SciPy filtfilt), and every pass starts
/// in the steady state of its first sample; the padding is removed afterwards.
/// `padding` is clamped to size - 1.
/// @throws std::invalid_argument if x has fewer than 2 samples.
Eigen::VectorXd filtfilt(const std::vector<SecondOrderSection>& sos, const Eigen::VectorXd& x, std::size_t padding);

/// Time derivative of a uniformly sampled (already low-pass filtered) signal
/// [unit/s] by fourth-order central differences,
///   (x[k-2] - 8 x[k-1] + 8 x[k+1] - x[k+2]) / (12 dt),
/// whose gain (8 sin(w dt) - sin(2 w dt)) / (6 dt) has a relative error of
/// about (w dt)^4 / 30 (5e-6 at 9 Hz and 512 Hz; the three-point central
/// difference would give (w dt)^2 / 6 = 2e-3, a coloured error comparable to
/// the equation error of good data). The smoothing is the low-pass applied
/// before. Second-order central differences at the second and second-last
/// sample, second-order one-sided differences (-3 x0 + 4 x1 - x2) / (2 dt)
/// at the ends (first-order for 2 samples).
Eigen::VectorXd differentiate(const Eigen::VectorXd& x, double rate_hz);

/// Options of the processing chain.
struct ProcessingOptions {
  double rate_hz = contract::kDefaultImuRateHz;         ///< uniform grid rate [Hz], > 0
  Interpolation interpolation = Interpolation::kCubic;  ///< of resample_uniform()
  int filter_order = 10;                                ///< Butterworth order, 1..40; 0 disables the low-pass
  double cutoff_hz = 9.0;                               ///< low-pass cut-off [Hz], in (0, rate/2)
  std::size_t padding = 0;                              ///< filtfilt edge padding [samples]; 0: default_padding()
};

/// Every signal of `u` low-pass filtered as `options` says (Butterworth of filter_order at cutoff_hz,
/// zero phase by filtfilt); order 0: `u` as it is.
/// @throws std::invalid_argument for an order outside 0..40 or a cut-off outside (0, rate/2).
UniformData lowpass_filtered(UniformData u, const ProcessingOptions& options);

/// Resamples, then low-pass filters every signal with filtfilt (lowpass_filtered).
/// @throws std::invalid_argument on invalid options (see butterworth_lowpass);
///         as resample_uniform.
UniformData process(const FlightData& data, const ProcessingOptions& options);

}  // namespace nimble::ident
