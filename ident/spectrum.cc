#include "ident/spectrum.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace nimble::ident {
namespace {

bool is_power_of_two(std::size_t n) { return n != 0 && (n & (n - 1)) == 0; }

/// One-sided scaling factor of bin k of an nfft-point transform.
double one_sided(std::size_t k, std::size_t nfft) { return (k == 0 || 2 * k == nfft) ? 1.0 : 2.0; }

}  // namespace

void fft_radix2(std::vector<std::complex<double>>& x) {
  const std::size_t n = x.size();
  if (!is_power_of_two(n))
    throw std::invalid_argument("fft_radix2: size " + std::to_string(n) + " is not a power of two");
  for (std::size_t i = 1, j = 0; i < n; ++i) {  // bit reversal
    std::size_t bit = n >> 1;
    for (; j & bit; bit >>= 1) j ^= bit;
    j ^= bit;
    if (i < j) std::swap(x[i], x[j]);
  }
  for (std::size_t len = 2; len <= n; len <<= 1) {
    const std::complex<double> step = std::polar(1.0, -2.0 * M_PI / static_cast<double>(len));
    for (std::size_t i = 0; i < n; i += len) {
      std::complex<double> w = 1.0;
      for (std::size_t k = 0; k < len / 2; ++k) {
        const std::complex<double> a = x[i + k];
        const std::complex<double> b = x[i + k + len / 2] * w;
        x[i + k] = a + b;
        x[i + k + len / 2] = a - b;
        w *= step;
      }
    }
  }
}

std::size_t next_power_of_two(std::size_t n) {
  std::size_t p = 1;
  while (p < n) p <<= 1;
  return p;
}

double Psd::integral() const { return psd.sum() * df_hz; }

double Psd::integral_up_to(double f_max_hz) const {
  double sum = 0.0;
  for (Eigen::Index k = 0; k < psd.size(); ++k) {
    if (f_hz[k] <= f_max_hz) sum += psd[k];
  }
  return sum * df_hz;
}

Psd periodogram(const Eigen::VectorXd& x, double rate_hz) {
  if (x.size() < 2) throw std::invalid_argument("periodogram needs at least 2 samples");
  if (!(rate_hz > 0.0)) throw std::invalid_argument("periodogram: rate must be positive");
  const std::size_t n = static_cast<std::size_t>(x.size());
  const std::size_t nfft = next_power_of_two(n);
  const double mean = x.mean();
  std::vector<std::complex<double>> buf(nfft, 0.0);
  for (std::size_t i = 0; i < n; ++i) buf[i] = x[static_cast<Eigen::Index>(i)] - mean;
  fft_radix2(buf);
  Psd out;
  out.df_hz = rate_hz / static_cast<double>(nfft);
  out.segments = 1;
  const std::size_t bins = nfft / 2 + 1;
  out.f_hz.resize(static_cast<Eigen::Index>(bins));
  out.psd.resize(static_cast<Eigen::Index>(bins));
  for (std::size_t k = 0; k < bins; ++k) {
    out.f_hz[static_cast<Eigen::Index>(k)] = static_cast<double>(k) * out.df_hz;
    out.psd[static_cast<Eigen::Index>(k)] = one_sided(k, nfft) * std::norm(buf[k]) / (rate_hz * static_cast<double>(n));
  }
  return out;
}

Psd welch(const Eigen::VectorXd& x, double rate_hz, std::size_t segment_length,
          const std::vector<std::pair<Eigen::Index, Eigen::Index>>& ranges_in) {
  if (!(rate_hz > 0.0)) throw std::invalid_argument("welch: rate must be positive");
  if (segment_length < 8) throw std::invalid_argument("welch: segment length must be >= 8 samples");
  std::vector<std::pair<Eigen::Index, Eigen::Index>> ranges = ranges_in;
  if (ranges.empty()) ranges.push_back({0, x.size()});
  Eigen::Index longest = 0;
  for (auto& r : ranges) {
    r.first = std::clamp<Eigen::Index>(r.first, 0, x.size());
    r.second = std::clamp<Eigen::Index>(r.second, r.first, x.size());
    longest = std::max(longest, r.second - r.first);
  }
  // Power of two not above the requested length nor the longest range.
  std::size_t nseg = next_power_of_two(segment_length);
  if (nseg > segment_length) nseg >>= 1;
  while (nseg > static_cast<std::size_t>(longest) && nseg > 8) nseg >>= 1;
  if (nseg > static_cast<std::size_t>(longest)) {
    throw std::invalid_argument("welch: no range holds a segment of 8 samples");
  }
  const Eigen::Index seg = static_cast<Eigen::Index>(nseg);
  const Eigen::Index hop = seg / 2;

  // Periodic Hann window (sums exactly for 50 % overlap).
  Eigen::VectorXd w(seg);
  for (Eigen::Index i = 0; i < seg; ++i)
    w[i] = 0.5 - 0.5 * std::cos(2.0 * M_PI * static_cast<double>(i) / static_cast<double>(seg));
  const double w2 = w.squaredNorm();

  const std::size_t bins = nseg / 2 + 1;
  Eigen::VectorXd acc = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(bins));
  std::size_t count = 0;
  std::vector<std::complex<double>> buf(nseg);
  for (const auto& r : ranges) {
    for (Eigen::Index start = r.first; start + seg <= r.second; start += hop) {
      const double mean = x.segment(start, seg).mean();
      for (Eigen::Index i = 0; i < seg; ++i) buf[static_cast<std::size_t>(i)] = w[i] * (x[start + i] - mean);
      fft_radix2(buf);
      for (std::size_t k = 0; k < bins; ++k)
        acc[static_cast<Eigen::Index>(k)] += one_sided(k, nseg) * std::norm(buf[k]);
      ++count;
    }
  }
  Psd out;
  out.df_hz = rate_hz / static_cast<double>(nseg);
  out.segments = count;
  out.f_hz.resize(static_cast<Eigen::Index>(bins));
  for (std::size_t k = 0; k < bins; ++k) out.f_hz[static_cast<Eigen::Index>(k)] = static_cast<double>(k) * out.df_hz;
  out.psd = acc / (rate_hz * w2 * static_cast<double>(count));
  return out;
}

Eigen::VectorXd autocorrelation(const Eigen::VectorXd& x, std::size_t max_lag) {
  const Eigen::Index n = x.size();
  if (n < 2) throw std::invalid_argument("autocorrelation needs at least 2 samples");
  const Eigen::Index lags = std::min<Eigen::Index>(static_cast<Eigen::Index>(max_lag), n - 1);
  const Eigen::VectorXd d = x.array() - x.mean();
  const double c0 = d.squaredNorm();
  Eigen::VectorXd rho = Eigen::VectorXd::Zero(lags + 1);
  rho[0] = 1.0;
  if (c0 <= 0.0) return rho;
  for (Eigen::Index tau = 1; tau <= lags; ++tau) {
    rho[tau] = d.head(n - tau).dot(d.tail(n - tau)) / c0;
  }
  return rho;
}

}  // namespace nimble::ident
