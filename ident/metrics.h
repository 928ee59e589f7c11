#pragma once
/// Accuracy metrics of an estimated output and residual whiteness
/// (thesis Section 5.1, Eqs 5.2-5.5).

#include <cstddef>
#include <string>

#include <Eigen/Dense>

namespace nimble::ident {

/// Accuracy of an estimate of one measured output.
struct FitMetrics {
  /// Pearson correlation of measured and estimated (Eq 5.5).
  double rxy = 0.0;
  /// Goodness of fit with the thesis's parameter penalty (Eq 5.2):
  /// R2 = 1 - SSres / SStot * (N - 1) / (N - P).
  double r2 = 0.0;
  /// Root mean square of measured - estimated (Eq 5.3), in the output's unit.
  double rmse = 0.0;
  /// max - min of the measured output, in its unit.
  double range = 0.0;
  /// 100 * rmse / range [%].
  double rmse_pct_range = 0.0;
  Eigen::Index samples = 0;
  int parameters = 0;  ///< P of Eq 5.2
};

/// Metrics of `estimated` against `measured` with P = `parameters` (use the
/// number of parameters estimated for this output; 1 gives the plain R2, for
/// data the parameters were not fitted to).
/// @throws std::invalid_argument if the sizes differ, N <= P or N < 2.
FitMetrics fit_metrics(const Eigen::VectorXd& measured, const Eigen::VectorXd& estimated, int parameters);

/// Whiteness test of a residual.
///
/// The residual is decimated by `lag_step` (so lag k is k * lag_step samples)
/// and its autocorrelation (Eq 5.4) compared with the 95 % bounds of white
/// noise, +-1.96 / sqrt(N_d), N_d the number of decimated samples. For
/// low-pass filtered data use lag_step = rate / (2 cutoff): samples of
/// band-limited white noise that far apart are (nearly) uncorrelated, while
/// at the full rate every filtered residual looks coloured.
/// Verdict: white when the number of lags 1..max_lag outside the bounds is at
/// most the 95 % quantile of Binomial(max_lag, 0.05), i.e. no more than white
/// noise gives in 95 % of records ("95 % of the lags inside the band", with
/// the scatter of a finite number of lags allowed for).
/// A residual too short for max_lag lags after decimation is not tested: `tested` is false and
/// `note` says how long a record the test needs (never an error: the rest of a report stands).
struct Whiteness {
  bool tested = true;             ///< false: too few samples for the lags; only `note` (and lags, lag_step) hold
  std::string note;               ///< why it was not tested, with the record length it needs ("" if tested)
  Eigen::VectorXd rho;            ///< autocorrelation at lags 0..max_lag (rho[0] = 1)
  std::size_t lag_step = 1;       ///< samples per lag
  double lag_step_s = 0.0;        ///< seconds per lag
  double bound = 0.0;             ///< 1.96 / sqrt(N_d)
  std::size_t lags = 0;           ///< lags tested (1..lags)
  std::size_t outside = 0;        ///< lags with |rho| > bound
  double fraction_outside = 0.0;  ///< outside / lags
  double allowed_fraction = 0.0;  ///< the verdict's limit on fraction_outside
  bool white = false;
};

/// Whiteness of `residual` sampled at rate_hz. With fewer than max_lag + 2 samples after
/// decimation the test is skipped (Whiteness::tested false, its note saying how long a record
/// it needs: whiteness_min_samples()).
/// @throws std::invalid_argument if max_lag or lag_step is 0.
Whiteness residual_whiteness(const Eigen::VectorXd& residual, double rate_hz, std::size_t max_lag,
                             std::size_t lag_step);

/// Fewest samples (at the full rate) the whiteness test needs for max_lag lags of lag_step
/// samples: max_lag + 2 after decimation, i.e. (max_lag + 1) lag_step + 1.
std::size_t whiteness_min_samples(std::size_t max_lag, std::size_t lag_step);

/// Smallest k with P(X <= k) >= q for X ~ Binomial(n, p).
std::size_t binomial_quantile(std::size_t n, double p, double q);

}  // namespace nimble::ident
