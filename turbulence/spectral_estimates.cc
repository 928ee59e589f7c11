#include "turbulence/spectral_estimates.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>
#include <vector>

#include <unsupported/Eigen/FFT>

#include "turbulence/uncertainty.h"

namespace nimble::turbulence {
namespace {

bool is_power_of_two(std::size_t n) { return n != 0 && (n & (n - 1)) == 0; }

void check_dt(double dt_s) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) throw std::invalid_argument("PSD estimate: dt must be > 0 and finite");
}

/// |FFT|^2 of `in` (length a power of two), bins 0 .. size/2.
Eigen::VectorXd power_half(const std::vector<double>& in) {
  static thread_local Eigen::FFT<double> fft;
  std::vector<std::complex<double>> out;
  fft.fwd(out, in);
  Eigen::VectorXd p(static_cast<Eigen::Index>(in.size() / 2 + 1));
  for (Eigen::Index k = 0; k < p.size(); ++k) p[k] = std::norm(out[static_cast<std::size_t>(k)]);
  return p;
}

}  // namespace

std::size_t next_power_of_two(std::size_t n) {
  std::size_t p = 1;
  while (p < n) p <<= 1;
  return p;
}

Eigen::VectorXd hann_window(std::size_t M) {
  Eigen::VectorXd w(static_cast<Eigen::Index>(M));
  for (std::size_t n = 0; n < M; ++n) {
    w[static_cast<Eigen::Index>(n)] =
        0.5 * (1.0 - std::cos(2.0 * M_PI * static_cast<double>(n) / static_cast<double>(M)));
  }
  return w;
}

SpectralEstimate periodogram(const Eigen::VectorXd& x, double dt_s) {
  check_dt(dt_s);
  const std::size_t N = static_cast<std::size_t>(x.size());
  if (N < 2) throw std::invalid_argument("periodogram: need at least 2 samples");
  const std::size_t nfft = next_power_of_two(N);
  const double mean = x.mean();
  std::vector<double> in(nfft, 0.0);
  for (std::size_t n = 0; n < N; ++n) in[n] = x[static_cast<Eigen::Index>(n)] - mean;
  SpectralEstimate e;
  e.method = "periodogram";
  e.psd = power_half(in) * (dt_s / static_cast<double>(N));
  e.d_omega_radps = 2.0 * M_PI / (static_cast<double>(nfft) * dt_s);
  e.omega_radps =
      Eigen::VectorXd::LinSpaced(e.psd.size(), 0.0, e.d_omega_radps * static_cast<double>(e.psd.size() - 1));
  e.record_length = N;
  e.segment_length = nfft;
  e.segments = 1;
  e.dof = 2.0;
  return e;
}

SpectralEstimate welch(const Eigen::VectorXd& x, double dt_s, std::size_t M) {
  check_dt(dt_s);
  const std::size_t N = static_cast<std::size_t>(x.size());
  if (!is_power_of_two(M) || M < 8 || M > N) {
    throw std::invalid_argument("welch: the segment length " + std::to_string(M) + " must be a power of two in [8, " +
                                std::to_string(N) + "]");
  }
  const std::size_t hop = M / 2;
  const std::size_t K = (N - M) / hop + 1;
  const Eigen::VectorXd w = hann_window(M);
  const double w2 = w.squaredNorm();
  const double mean = x.mean();
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(M / 2 + 1));
  std::vector<double> in(M);
  for (std::size_t s = 0; s < K; ++s) {
    for (std::size_t n = 0; n < M; ++n) {
      in[n] = w[static_cast<Eigen::Index>(n)] * (x[static_cast<Eigen::Index>(s * hop + n)] - mean);
    }
    sum += power_half(in);
  }
  SpectralEstimate e;
  e.method = "welch";
  e.psd = sum * (dt_s / (w2 * static_cast<double>(K)));
  e.d_omega_radps = 2.0 * M_PI / (static_cast<double>(M) * dt_s);
  e.omega_radps =
      Eigen::VectorXd::LinSpaced(e.psd.size(), 0.0, e.d_omega_radps * static_cast<double>(e.psd.size() - 1));
  e.record_length = N;
  e.segment_length = M;
  e.segments = K;
  e.dof = welch_dof(K, M);
  return e;
}

Eigen::VectorXd welch_expectation(const Eigen::VectorXd& autocovariance, double dt_s, std::size_t M, std::size_t bins) {
  check_dt(dt_s);
  if (!is_power_of_two(M) || M < 8 || bins > M / 2 + 1 || autocovariance.size() == 0) {
    throw std::invalid_argument(
        "welch_expectation: need M a power of two >= 8, at most M/2 + 1 bins and an "
        "autocovariance");
  }
  const Eigen::VectorXd w = hann_window(M);
  const Eigen::Index lags = std::min<Eigen::Index>(autocovariance.size(), static_cast<Eigen::Index>(M));
  // a_m R_m for m = 0 .. lags - 1.
  Eigen::VectorXd aR(lags);
  for (Eigen::Index m = 0; m < lags; ++m) {
    const Eigen::Index len = static_cast<Eigen::Index>(M) - m;
    aR[m] = w.head(len).dot(w.segment(m, len)) * autocovariance[m];
  }
  // The lags -m wrap to M - m: one DFT of length M gives every bin.
  std::vector<double> y(M, 0.0);
  y[0] = aR[0];
  for (Eigen::Index m = 1; m < lags; ++m) {
    y[static_cast<std::size_t>(m)] += aR[m];
    y[M - static_cast<std::size_t>(m)] += aR[m];
  }
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> Y;
  fft.fwd(Y, y);
  Eigen::VectorXd out(static_cast<Eigen::Index>(bins));
  const double scale = dt_s / w.squaredNorm();
  for (Eigen::Index k = 0; k < out.size(); ++k) out[k] = scale * Y[static_cast<std::size_t>(k)].real();
  return out;
}

std::size_t default_welch_segment(std::size_t n) {
  std::size_t M = 64;
  while (2 * M <= n / 8) M *= 2;
  return M <= n ? M : (next_power_of_two(n + 1) / 2);
}

double variance_from_estimate(const SpectralEstimate& e) {
  const Eigen::Index last = e.psd.size() - 1;
  if (last < 1) return 0.0;
  const double interior = e.psd.segment(1, last - 1).sum();
  return e.d_omega_radps / M_PI * (0.5 * e.psd[0] + interior + 0.5 * e.psd[last]);
}

double sample_variance(const Eigen::VectorXd& x) {
  if (x.size() < 2) throw std::invalid_argument("sample_variance: need at least 2 samples");
  return (x.array() - x.mean()).square().sum() / static_cast<double>(x.size() - 1);
}

}  // namespace nimble::turbulence
