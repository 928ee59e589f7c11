#pragma once
/// Chi-square distribution functions: innovation gating and consistency tests (estimator),
/// significance of regression terms (discrepancy/discrepancy.h).

namespace nimble {

/// Regularised lower incomplete gamma function P(a, x) [-], a > 0, x >= 0.
/// @throws std::invalid_argument for a <= 0, x < 0 or non-finite arguments.
double regularized_gamma_p(double a, double x);

/// Cumulative distribution function of the chi-square distribution with `dof` degrees of freedom.
/// @throws std::invalid_argument for dof <= 0 or x non-finite.
double chi_square_cdf(double x, double dof);

/// Upper tail 1 - chi_square_cdf(x, dof), computed directly so that it keeps its relative
/// accuracy far into the tail (e.g. chi_square_survival(20, 1) = 7.74e-6).
/// @throws std::invalid_argument for dof <= 0 or x non-finite.
double chi_square_survival(double x, double dof);

/// Quantile x with chi_square_cdf(x, dof) = p, to a relative accuracy of about 1e-12.
/// Example: chi_square_quantile(0.999, 6) = 22.458 (innovation gate of a 6-dof measurement).
/// @throws std::invalid_argument unless dof > 0 and 0 < p < 1.
double chi_square_quantile(double p, double dof);

}  // namespace nimble
