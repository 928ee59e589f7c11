#include "turbulence/uncertainty.h"

#include <cmath>
#include <complex>
#include <limits>
#include <stdexcept>
#include <vector>

#include <unsupported/Eigen/FFT>

#include "core/chi_square.h"
#include "turbulence/spectral_density.h"
#include "turbulence/spectral_estimates.h"

namespace nimble::turbulence {

Eigen::VectorXd sampled_autocovariance(const Eigen::MatrixXd& Phi, const Eigen::MatrixXd& P,
                                       const Eigen::RowVectorXd& c, std::size_t max_lag, double rel_tol) {
  Eigen::VectorXd v = P * c.transpose();
  const double v0 = v.norm();
  std::vector<double> R;
  R.push_back(c.dot(v));
  for (std::size_t k = 1; k <= max_lag && v0 > 0.0; ++k) {
    v = Phi * v;
    R.push_back(c.dot(v));
    if (v.norm() < rel_tol * v0) break;
  }
  return Eigen::Map<Eigen::VectorXd>(R.data(), static_cast<Eigen::Index>(R.size()));
}

Eigen::VectorXd weight_autocorrelation(const Eigen::VectorXd& q, std::size_t max_lag) {
  if (q.size() == 0) throw std::invalid_argument("weight_autocorrelation: empty weights");
  const std::size_t N = static_cast<std::size_t>(q.size());
  const std::size_t lags = std::min(max_lag + 1, N);
  const std::size_t L = next_power_of_two(2 * N);
  std::vector<double> in(L, 0.0);
  for (std::size_t n = 0; n < N; ++n) in[n] = q[static_cast<Eigen::Index>(n)];
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> Q;
  fft.fwd(Q, in);
  for (auto& z : Q) z = std::norm(z);
  std::vector<std::complex<double>> corr;
  fft.inv(corr, Q);
  Eigen::VectorXd c(static_cast<Eigen::Index>(lags));
  for (std::size_t k = 0; k < lags; ++k) c[static_cast<Eigen::Index>(k)] = corr[k].real();
  return c;
}

double quadratic_estimate_std_from_correlation(const Eigen::VectorXd& c, const Eigen::VectorXd& R) {
  if (c.size() == 0 || R.size() == 0) throw std::invalid_argument("quadratic_estimate_std: empty input");
  const Eigen::Index lags = std::min(c.size(), R.size());
  double sum = c[0] * R[0] * R[0];
  for (Eigen::Index k = 1; k < lags; ++k) sum += 2.0 * c[k] * R[k] * R[k];
  return std::sqrt(std::max(0.0, 2.0 * sum));
}

double quadratic_estimate_std(const Eigen::VectorXd& q, const Eigen::VectorXd& R) {
  if (q.size() == 0 || R.size() == 0)
    throw std::invalid_argument("quadratic_estimate_std: empty weights or autocovariance");
  return quadratic_estimate_std_from_correlation(weight_autocorrelation(q, static_cast<std::size_t>(R.size())), R);
}

Eigen::VectorXd sample_variance_weights(std::size_t N) {
  return Eigen::VectorXd::Constant(static_cast<Eigen::Index>(N), 1.0 / (static_cast<double>(N) - 1.0));
}

Eigen::VectorXd periodogram_variance_weights(std::size_t N) {
  return Eigen::VectorXd::Constant(static_cast<Eigen::Index>(N), 1.0 / static_cast<double>(N));
}

Eigen::VectorXd welch_variance_weights(std::size_t N, std::size_t M) {
  if (M < 2 || M > N) throw std::invalid_argument("welch_variance_weights: need 2 <= M <= N");
  const std::size_t hop = M / 2;
  const std::size_t K = (N - M) / hop + 1;
  const Eigen::VectorXd w = hann_window(M);
  const Eigen::VectorXd w2 = w.cwiseAbs2() / (w.squaredNorm() * static_cast<double>(K));
  Eigen::VectorXd q = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(N));
  for (std::size_t s = 0; s < K; ++s) q.segment(static_cast<Eigen::Index>(s * hop), static_cast<Eigen::Index>(M)) += w2;
  return q;
}

double sample_variance_std_from_psd(const std::function<double(double)>& psd, double T_s) {
  if (!(T_s > 0.0)) throw std::invalid_argument("sample_variance_std_from_psd: T must be > 0");
  const Quadrature q = integrate_psd(
      [&](double w) {
        const double s = psd(w);
        return s * s;
      },
      std::numeric_limits<double>::infinity(), 1.0, 1e-8);
  return std::sqrt(2.0 / T_s * q.value);
}

double welch_dof(std::size_t K, std::size_t M) {
  if (K == 0 || M < 2) return 0.0;
  const Eigen::VectorXd w = hann_window(M);
  const double w2 = w.squaredNorm();
  const std::size_t hop = M / 2;
  double corr = 0.0;
  for (std::size_t j = 1; j < K && j * hop < M; ++j) {
    const Eigen::Index lag = static_cast<Eigen::Index>(j * hop);
    const double overlap = w.head(static_cast<Eigen::Index>(M) - lag).dot(w.tail(static_cast<Eigen::Index>(M) - lag));
    const double rho = overlap * overlap / (w2 * w2);
    corr += (1.0 - static_cast<double>(j) / static_cast<double>(K)) * rho;
  }
  return 2.0 * static_cast<double>(K) / (1.0 + 2.0 * corr);
}

ConfidenceBand psd_confidence_band(double dof, double level) {
  if (!(dof > 0.0) || !(level > 0.0 && level < 1.0)) {
    throw std::invalid_argument("psd_confidence_band: need dof > 0 and 0 < level < 1");
  }
  ConfidenceBand b;
  b.lower = chi_square_quantile(0.5 * (1.0 - level), dof) / dof;
  b.upper = chi_square_quantile(0.5 * (1.0 + level), dof) / dof;
  return b;
}

std::size_t binomial_upper_quantile(std::size_t n, double p, double level) {
  if (!(p >= 0.0 && p <= 1.0) || !(level > 0.0 && level < 1.0)) {
    throw std::invalid_argument("binomial_upper_quantile: need 0 <= p <= 1 and 0 < level < 1");
  }
  if (p == 0.0) return 0;
  if (p == 1.0) return n;
  // P(X = k) by the recursion P(k+1) = P(k) (n - k) / (k + 1) p / (1 - p), in logs from P(0).
  const double log_ratio = std::log(p) - std::log1p(-p);
  double log_pk = static_cast<double>(n) * std::log1p(-p);
  double cumulative = std::exp(log_pk);
  std::size_t c = 0;
  while (cumulative < level && c < n) {
    log_pk += std::log(static_cast<double>(n - c)) - std::log(static_cast<double>(c + 1)) + log_ratio;
    ++c;
    cumulative += std::exp(log_pk);
  }
  return c;
}

}  // namespace nimble::turbulence
