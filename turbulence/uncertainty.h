#pragma once
/// Statistical uncertainty of PSD and variance estimates from a finite record of a stationary
/// Gaussian process (PSD convention of spectral_density.h).
///
/// Variance estimates. Every variance estimate of this library is (up to the removal of the
/// record mean, an O(1/N) effect that is neglected) a quadratic form v = sum_n q_n x_n^2 with
/// weights q_n >= 0 summing to about 1:
///   sample variance      q_n = 1 / (N - 1);
///   periodogram integral q_n = 1 / N (Parseval: the integral is the 1/N sample variance);
///   Welch integral       q_n = (1/K) sum_segments w_{n - s hop}^2 / sum w^2.
/// For a zero-mean Gaussian x with autocovariance R_k, Isserlis' theorem gives
/// cov(x_n^2, x_m^2) = 2 R_{n-m}^2, hence exactly
///   var(v) = 2 sum_n sum_m q_n q_m R_{n-m}^2 = 2 sum_k c_k R_k^2,  c_k = sum_n q_n q_{n+k}.
/// For the sample variance, c_k = (N - |k|)/(N-1)^2 ~ 1/N, so var(s^2) ~ (2/N) sum_k R_k^2
/// = (2/N) R_0^2 sum_k rho_k^2. With R_k = R(k dt) and dt short against the correlation time,
/// sum_k R_k^2 ~ (1/dt) int R(tau)^2 d tau, and by Parseval int R^2 d tau =
/// (1/2pi) int_{-inf}^{inf} S^2 d omega = (1/pi) int_0^inf S^2 d omega, so with T = N dt
///   var(s^2) ~ (2/T) (1/pi) int_0^inf S(omega)^2 d omega   (sample_variance_std_from_psd()).
/// White-noise check: a process of variance sigma^2 and bandwidth B (S = pi sigma^2 / B on
/// [0, B]) gives var(s^2) = 2 sigma^4 / (T B / pi) = 2 sigma^4 / N_eff with N_eff = T B / pi
/// independent samples (B = pi / dt: N samples, the textbook 2 sigma^4 / N).
///
/// PSD estimates. An interior bin of an estimate is, for a smooth spectrum, S chi^2_nu / nu:
/// nu = 2 for the periodogram (its relative standard deviation is 1 at any record length);
/// for Welch with K segments (Welch 1967) nu = 2 K / (1 + 2 sum_{j=1}^{K-1} (1 - j/K) rho_j),
/// rho_j = (sum_n w_n w_{n + j hop})^2 / (sum_n w_n^2)^2 the correlation of segment
/// periodograms j hops apart (Hann, 50 % overlap: rho_1 = 1/36, nu ~ 1.89 K). The bins at
/// omega = 0 and at Nyquist have half those degrees of freedom.

#include <cstddef>
#include <functional>

#include <Eigen/Dense>

namespace nimble::turbulence {

/// Autocovariance R_k = c Phi^k P c' of the sampled stationary output y = c x, k = 0 .. until
/// |Phi^k P c'| has fallen below rel_tol of |P c'| (or max_lag). [output unit^2]
Eigen::VectorXd sampled_autocovariance(const Eigen::MatrixXd& Phi, const Eigen::MatrixXd& P,
                                       const Eigen::RowVectorXd& c, std::size_t max_lag, double rel_tol = 1e-7);

/// Standard deviation of the quadratic estimate sum_n q_n x_n^2 of a zero-mean Gaussian process
/// with autocovariance R_0.. (lags beyond its end taken as 0): sqrt(2 sum_k c_k R_|k|^2).
/// @throws std::invalid_argument if q or R is empty.
double quadratic_estimate_std(const Eigen::VectorXd& q, const Eigen::VectorXd& autocovariance);

/// c_k = sum_n q_n q_{n+k}, k = 0 .. max_lag (clamped to q.size() - 1), by FFT. It depends on
/// the estimator and the record length only, so one c serves every output.
Eigen::VectorXd weight_autocorrelation(const Eigen::VectorXd& q, std::size_t max_lag);

/// sqrt(2 sum_k c_k R_|k|^2) from a weight autocorrelation c (weight_autocorrelation()).
double quadratic_estimate_std_from_correlation(const Eigen::VectorXd& c, const Eigen::VectorXd& autocovariance);

/// Weights q of the sample variance 1/(N-1) (var.m).
Eigen::VectorXd sample_variance_weights(std::size_t N);
/// Weights q of the periodogram integral (1/N).
Eigen::VectorXd periodogram_variance_weights(std::size_t N);
/// Weights q of the Welch integral: Hann segments of M, hop M/2, over N samples.
/// @throws std::invalid_argument if M > N or M < 2.
Eigen::VectorXd welch_variance_weights(std::size_t N, std::size_t M);

/// Continuous-time approximation of the standard deviation of the sample variance of a record
/// of T seconds: sqrt((2/T) (1/pi) int_0^inf S^2 d omega).
/// @throws std::invalid_argument if T is not > 0.
double sample_variance_std_from_psd(const std::function<double(double)>& psd, double T_s);

/// Equivalent degrees of freedom of an interior Welch bin (Hann, M samples, hop M/2, K segments).
double welch_dof(std::size_t segments, std::size_t segment_length);

/// Multipliers [lower, upper] of the true S between which an estimate with `dof` degrees of
/// freedom falls with probability `level` (chi^2 quantiles (1 -+ level)/2 over dof).
/// @throws std::invalid_argument unless dof > 0 and 0 < level < 1.
struct ConfidenceBand {
  double lower = 0.0;
  double upper = 0.0;
};
ConfidenceBand psd_confidence_band(double dof, double level);

/// Smallest c with P(X <= c) >= level for X ~ Binomial(n, p): the most bins of n independent
/// ones that may fall outside a band of coverage 1 - p before the agreement is rejected at
/// the false-alarm rate 1 - level. (Adjacent Welch bins of a Hann window are correlated,
/// rho = 4/9 for the power; bins two apart nearly not, rho = 1/36: count every other bin.)
/// @throws std::invalid_argument unless 0 <= p <= 1 and 0 < level < 1.
std::size_t binomial_upper_quantile(std::size_t n, double p, double level);

}  // namespace nimble::turbulence
