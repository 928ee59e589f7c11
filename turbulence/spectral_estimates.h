#pragma once
/// PSD estimates from a sampled record, in the library's convention (spectral_density.h):
/// two-sided S in unit^2/(rad/s) against omega in rad/s, sigma^2 = (1/pi) int_0^inf S d omega.
/// Neither estimate is doubled for one-sided use.
///
/// Periodogram (rectangular window): record mean removed, zero-padded to N_fft = the next
/// power of two >= N, S_k = (dt / N) |X_k|^2 with X_k = sum_n x_n exp(-2 pi i k n / N_fft),
/// omega_k = 2 pi k / (N_fft dt), k = 0 .. N_fft/2. Zero padding interpolates the spectrum and
/// keeps Parseval: variance_from_estimate() of it is the mean-removed (1/N) sample variance.
///
/// Welch: record mean removed once; segments of M samples (a power of two), 50 % overlap
/// (hop M/2, K = floor((N - M) / (M/2)) + 1 segments, the tail that does not fill a segment
/// is not used), periodic Hann window w_n = 0.5 (1 - cos(2 pi n / M)),
/// S_k = (1/K) sum_segments dt |sum_n w_n x_n exp(-2 pi i k n / M)|^2 / sum_n w_n^2,
/// omega_k = 2 pi k / (M dt). Its variance_from_estimate() is the window-weighted mean square.
/// Default M: the largest power of two <= N / 8 (at least 64): about 15 segments.
///
/// variance_from_estimate(): the trapezoid (1/pi) sum over 0 .. pi/dt with half weight at
/// omega = 0 and at the Nyquist frequency.

#include <cstddef>
#include <string>

#include <Eigen/Dense>

namespace nimble::turbulence {

/// A PSD estimate on its bins.
struct SpectralEstimate {
  std::string method;              ///< "periodogram" or "welch"
  Eigen::VectorXd omega_radps;     ///< bins 0 .. Nyquist
  Eigen::VectorXd psd;             ///< [unit^2/(rad/s)]
  double d_omega_radps = 0.0;      ///< bin spacing
  std::size_t record_length = 0;   ///< samples used
  std::size_t segment_length = 0;  ///< N_fft (periodogram) or M (Welch)
  std::size_t segments = 1;        ///< K (1 for the periodogram)
  double dof = 2.0;                ///< equivalent chi-square degrees of freedom of an interior bin
};

/// Periodogram of x sampled at dt. @throws std::invalid_argument if x has < 2 samples or dt <= 0.
SpectralEstimate periodogram(const Eigen::VectorXd& x, double dt_s);

/// Welch's estimate with Hann segments of M samples, 50 % overlap.
/// @throws std::invalid_argument unless M is a power of two, 8 <= M <= x.size(), dt > 0.
SpectralEstimate welch(const Eigen::VectorXd& x, double dt_s, std::size_t segment_length);

/// The default Welch segment length for n samples (see the header comment).
std::size_t default_welch_segment(std::size_t n);

/// Expected value of welch() with Hann segments of M samples for a zero-mean stationary
/// process with autocovariance R_k = R(k dt) (k = 0 .. ; lags beyond its end taken as 0), at
/// the Welch bins k = 0 .. bins - 1 (omega_k = 2 pi k / (M dt)):
///   E[S_k] = (dt / sum w^2) sum_{|m| < M} a_|m| R_|m| cos(omega_k m dt),  a_m = sum_n w_n w_{n+m}.
/// It holds the window's leakage and the aliasing of the sampled process exactly (it neglects
/// the removal of the record mean, which only touches the lowest bin or two). Use it as the
/// centre of the confidence band where the analytical PSD curves on the scale of a bin.
/// @throws std::invalid_argument unless M is a power of two >= 8, bins <= M/2 + 1, dt > 0 and
///         the autocovariance is not empty.
Eigen::VectorXd welch_expectation(const Eigen::VectorXd& autocovariance, double dt_s, std::size_t M, std::size_t bins);

/// The periodic Hann window of length M.
Eigen::VectorXd hann_window(std::size_t M);

/// (1/pi) int_0^{pi/dt} S d omega by the trapezoid over the estimate's bins [unit^2].
double variance_from_estimate(const SpectralEstimate& e);

/// Sample variance 1/(N-1) sum (x - mean)^2 (the practical's var.m).
/// @throws std::invalid_argument if x has < 2 samples.
double sample_variance(const Eigen::VectorXd& x);

/// Smallest power of two >= n (1 for n = 0).
std::size_t next_power_of_two(std::size_t n);

}  // namespace nimble::turbulence
