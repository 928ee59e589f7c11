#include "ident/metrics.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "ident/spectrum.h"

namespace nimble::ident {

FitMetrics fit_metrics(const Eigen::VectorXd& measured, const Eigen::VectorXd& estimated, int parameters) {
  const Eigen::Index n = measured.size();
  if (estimated.size() != n) {
    throw std::invalid_argument("fit_metrics: " + std::to_string(n) + " measured and " +
                                std::to_string(estimated.size()) + " estimated samples");
  }
  if (n < 2 || n <= parameters) {
    throw std::invalid_argument("fit_metrics: " + std::to_string(n) + " samples for " + std::to_string(parameters) +
                                " parameters");
  }
  FitMetrics m;
  m.samples = n;
  m.parameters = parameters;
  const Eigen::VectorXd dm = measured.array() - measured.mean();
  const Eigen::VectorXd de = estimated.array() - estimated.mean();
  const double sxx = dm.squaredNorm(), syy = de.squaredNorm();
  m.rxy = (sxx > 0.0 && syy > 0.0) ? dm.dot(de) / std::sqrt(sxx * syy) : 0.0;
  const double ss_res = (measured - estimated).squaredNorm();
  const double nd = static_cast<double>(n);
  m.r2 = sxx > 0.0 ? 1.0 - ss_res / sxx * (nd - 1.0) / (nd - parameters) : 0.0;
  m.rmse = std::sqrt(ss_res / nd);
  m.range = measured.maxCoeff() - measured.minCoeff();
  m.rmse_pct_range = m.range > 0.0 ? 100.0 * m.rmse / m.range : INFINITY;
  return m;
}

std::size_t binomial_quantile(std::size_t n, double p, double q) {
  double pmf = std::pow(1.0 - p, static_cast<double>(n));
  double cdf = pmf;
  std::size_t k = 0;
  while (cdf < q && k < n) {
    pmf *= static_cast<double>(n - k) / static_cast<double>(k + 1) * p / (1.0 - p);
    ++k;
    cdf += pmf;
  }
  return k;
}

Whiteness residual_whiteness(const Eigen::VectorXd& residual, double rate_hz, std::size_t max_lag,
                             std::size_t lag_step) {
  if (max_lag == 0 || lag_step == 0) throw std::invalid_argument("whiteness: max_lag and lag_step must be >= 1");
  const Eigen::Index step = static_cast<Eigen::Index>(lag_step);
  const Eigen::Index nd = (residual.size() + step - 1) / step;
  Whiteness w;
  w.lag_step = lag_step;
  w.lag_step_s = static_cast<double>(lag_step) / rate_hz;
  w.lags = max_lag;
  if (nd < static_cast<Eigen::Index>(max_lag) + 2) {
    // Too short for the lags: say how long a record the test needs, and go on without it.
    const std::size_t need = whiteness_min_samples(max_lag, lag_step);
    const double have_s = residual.size() > 0 ? static_cast<double>(residual.size() - 1) / rate_hz : 0.0;
    char buf[320];
    std::snprintf(buf, sizeof buf,
                  "whiteness skipped: needs at least %.2f s of data at this decimation (%zu lags of %zu samples, "
                  "%zu samples at %.6g Hz), the record has %.2f s",
                  static_cast<double>(need - 1) / rate_hz, max_lag, lag_step, need, rate_hz, have_s);
    w.tested = false;
    w.note = buf;
    return w;
  }
  Eigen::VectorXd dec(nd);
  for (Eigen::Index i = 0; i < nd; ++i) dec[i] = residual[i * step];
  w.rho = autocorrelation(dec, max_lag);
  w.bound = 1.96 / std::sqrt(static_cast<double>(nd));
  for (std::size_t k = 1; k <= max_lag; ++k) {
    if (std::fabs(w.rho[static_cast<Eigen::Index>(k)]) > w.bound) ++w.outside;
  }
  w.fraction_outside = static_cast<double>(w.outside) / static_cast<double>(max_lag);
  const std::size_t allowed = binomial_quantile(max_lag, 0.05, 0.95);
  w.allowed_fraction = static_cast<double>(allowed) / static_cast<double>(max_lag);
  w.white = w.outside <= allowed;
  return w;
}

std::size_t whiteness_min_samples(std::size_t max_lag, std::size_t lag_step) { return (max_lag + 1) * lag_step + 1; }

}  // namespace nimble::ident
