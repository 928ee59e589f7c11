#pragma once
/// Power spectral densities and autocorrelation (identifiability and residual
/// analysis, thesis Sections 5.1.2 and 7.4).
///
/// PSD scaling (periodogram and Welch): one-sided, in unit^2/Hz, with the mean
/// removed, so that the sum of psd * df over all bins equals the variance of
/// the signal (Parseval): exactly for the periodogram, in expectation for Welch.
/// The bins are f_k = k df, df = rate / nfft, k = 0 .. nfft/2; the DC and
/// Nyquist bins are not doubled, every other bin is.

#include <complex>
#include <cstddef>
#include <vector>

#include <Eigen/Dense>

namespace nimble::ident {

/// In-place radix-2 FFT, X_k = sum_n x_n exp(-2 pi i k n / N).
/// @throws std::invalid_argument unless the size is a power of two.
void fft_radix2(std::vector<std::complex<double>>& x);

/// Smallest power of two >= n (1 for n = 0).
std::size_t next_power_of_two(std::size_t n);

/// A one-sided power spectral density.
struct Psd {
  Eigen::VectorXd f_hz;      ///< bin frequencies [Hz]
  Eigen::VectorXd psd;       ///< [unit^2/Hz]
  double df_hz = 0.0;        ///< bin spacing [Hz]
  std::size_t segments = 0;  ///< number of averaged segments (1 for the periodogram)

  /// Sum of psd * df over all bins [unit^2]: the variance of the signal.
  double integral() const;
  /// Sum of psd * df over the bins with f <= f_max_hz [unit^2].
  double integral_up_to(double f_max_hz) const;
};

/// Periodogram of x (rectangular window, mean removed): psd_k = c |X_k|^2 /
/// (rate N) with c = 2 except at DC and Nyquist; x is zero-padded to the next
/// power of two, which interpolates the spectrum and keeps Parseval exact.
/// @throws std::invalid_argument if x has fewer than 2 samples or rate_hz <= 0.
Psd periodogram(const Eigen::VectorXd& x, double rate_hz);

/// Welch's method: Hann-windowed segments of `segment_length` samples (rounded
/// down to a power of two and to the data length), 50 % overlap, mean removed
/// per segment, psd_k = c |X_k|^2 / (rate sum w^2) averaged over segments.
/// Segments are taken inside each of `ranges` ([first, last) sample indices)
/// and averaged together; an empty `ranges` means the whole signal. Ranges
/// shorter than the segment are skipped.
/// @throws std::invalid_argument if no range holds one segment, segment_length < 8 or rate_hz <= 0.
Psd welch(const Eigen::VectorXd& x, double rate_hz, std::size_t segment_length,
          const std::vector<std::pair<Eigen::Index, Eigen::Index>>& ranges = {});

/// Normalised autocorrelation of x (thesis Eq 5.4, mean removed, biased
/// estimator 1/N): rho[tau] = C(tau) / C(0) for tau = 0 .. max_lag
/// (max_lag clamped to size - 1). A constant signal gives rho = 1, 0, 0, ...
/// @throws std::invalid_argument if x has fewer than 2 samples.
Eigen::VectorXd autocorrelation(const Eigen::VectorXd& x, std::size_t max_lag);

}  // namespace nimble::ident
