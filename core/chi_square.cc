#include "core/chi_square.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace nimble {
namespace {

// Series expansion of P(a, x), converges for x < a + 1.
double gamma_p_series(double a, double x) {
  double sum = 1.0 / a, term = sum, ap = a;
  for (int n = 0; n < 100000; ++n) {
    ap += 1.0;
    term *= x / ap;
    sum += term;
    if (std::fabs(term) < std::fabs(sum) * 1e-16) break;
  }
  return sum * std::exp(-x + a * std::log(x) - std::lgamma(a));
}

// Continued fraction of Q(a, x) = 1 - P(a, x) (modified Lentz), for x >= a + 1.
double gamma_q_continued_fraction(double a, double x) {
  const double tiny = std::numeric_limits<double>::min() / std::numeric_limits<double>::epsilon();
  double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
  for (int i = 1; i < 100000; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::fabs(d) < tiny) d = tiny;
    c = b + an / c;
    if (std::fabs(c) < tiny) c = tiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::fabs(delta - 1.0) < 1e-16) break;
  }
  return std::exp(-x + a * std::log(x) - std::lgamma(a)) * h;
}

}  // namespace

double regularized_gamma_p(double a, double x) {
  if (!(a > 0.0) || !(x >= 0.0) || !std::isfinite(a) || !std::isfinite(x)) {
    throw std::invalid_argument("regularized_gamma_p: need a > 0 and finite x >= 0, got a = " + std::to_string(a) +
                                ", x = " + std::to_string(x));
  }
  if (x == 0.0) return 0.0;
  if (x < a + 1.0) return gamma_p_series(a, x);
  return 1.0 - gamma_q_continued_fraction(a, x);
}

double chi_square_cdf(double x, double dof) {
  if (!(dof > 0.0) || !std::isfinite(x)) {
    throw std::invalid_argument("chi_square_cdf: need dof > 0 and finite x");
  }
  if (x <= 0.0) return 0.0;
  return regularized_gamma_p(0.5 * dof, 0.5 * x);
}

double chi_square_survival(double x, double dof) {
  if (!(dof > 0.0) || !std::isfinite(x)) {
    throw std::invalid_argument("chi_square_survival: need dof > 0 and finite x");
  }
  if (x <= 0.0) return 1.0;
  const double a = 0.5 * dof, h = 0.5 * x;
  if (h < a + 1.0) return 1.0 - gamma_p_series(a, h);
  return gamma_q_continued_fraction(a, h);
}

double chi_square_quantile(double p, double dof) {
  if (!(dof > 0.0) || !(p > 0.0 && p < 1.0)) {
    throw std::invalid_argument("chi_square_quantile: need dof > 0 and 0 < p < 1, got dof = " + std::to_string(dof) +
                                ", p = " + std::to_string(p));
  }
  // Bracket, then bisection (the CDF is monotonic); 200 halvings reach machine precision.
  double lo = 0.0, hi = std::max(1.0, dof);
  while (chi_square_cdf(hi, dof) < p) hi *= 2.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (chi_square_cdf(mid, dof) < p)
      lo = mid;
    else
      hi = mid;
    if (hi - lo <= 1e-13 * hi) break;
  }
  return 0.5 * (lo + hi);
}

}  // namespace nimble
