#include "detection_power/power_curve.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace nimble::detection_power {
namespace {

std::string text_4g(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", x);
  return text;
}

/// The non-decreasing least-squares fit of `p` weighted by `w` (pool-adjacent-violators).
std::vector<double> isotonic(const std::vector<double>& p, const std::vector<double>& w) {
  std::vector<double> level, weight;
  std::vector<std::size_t> width;
  for (std::size_t i = 0; i < p.size(); ++i) {
    level.push_back(p[i]);
    weight.push_back(w[i]);
    width.push_back(1);
    while (level.size() > 1 && level[level.size() - 2] > level.back()) {
      const std::size_t k = level.size() - 1;
      level[k - 1] = (level[k - 1] * weight[k - 1] + level[k] * weight[k]) / (weight[k - 1] + weight[k]);
      weight[k - 1] += weight[k];
      width[k - 1] += width[k];
      level.pop_back();
      weight.pop_back();
      width.pop_back();
    }
  }
  std::vector<double> out;
  for (std::size_t b = 0; b < level.size(); ++b) out.insert(out.end(), width[b], level[b]);
  return out;
}

}  // namespace

double normal_quantile(double q) {
  // Newton's method on Phi(z) - q from a logistic start; Phi through erfc.
  double z = std::log(q / (1 - q)) / 1.7;
  for (int it = 0; it < 60; ++it) {
    const double f = 0.5 * std::erfc(-z / std::sqrt(2.0)) - q;
    const double d = std::exp(-0.5 * z * z) / 2.5066282746310002;
    const double step = f / d;
    z -= step;
    if (std::fabs(step) < 1e-12) break;
  }
  return z;
}

Crossing crossing(const std::vector<double>& x, const std::vector<Proportion>& props, double target, bool sqrt_x) {
  Crossing r;
  r.value = std::numeric_limits<double>::quiet_NaN();
  const std::size_t m = x.size();
  if (m == 0) {
    r.note = "nothing flown";
    return r;
  }
  std::vector<double> est, w;
  for (const Proportion& q : props) {
    est.push_back(q.p);
    w.push_back(std::max(1, q.n));
  }
  const std::vector<double> p = isotonic(est, w);
  if (p[0] >= target) {
    r.reached = true;
    r.value = x[0];
    r.note = "at or below " + text_4g(x[0]) + ", the first value flown";
    return r;
  }
  const auto axis = [sqrt_x](double v) { return sqrt_x ? std::sqrt(std::fabs(v)) : std::fabs(v); };
  const auto probit = [](double q, int n) {
    const double e = 0.5 / std::max(1, n);
    return normal_quantile(std::clamp(q, e, 1.0 - e));
  };
  const double zt = normal_quantile(target);
  for (std::size_t i = 1; i < m; ++i) {
    if (p[i] < target) continue;
    const double z0 = probit(p[i - 1], props[i - 1].n), z1 = probit(p[i], props[i].n);
    const double a0 = axis(x[i - 1]), a1 = axis(x[i]);
    const double f = z1 > z0 ? std::clamp((zt - z0) / (z1 - z0), 0.0, 1.0) : 1.0;
    double a = a0 + f * (a1 - a0);
    // With three or more cells inside the transition (0 < P < 1), the line fitted to all of them
    // instead: the end above the target was chosen for its estimate reaching it, which biases a
    // two-point interpolation toward the short side; the fit pools that end with its neighbours.
    double sw = 0, sa = 0, sz = 0, saa = 0, saz = 0;
    int inside = 0;
    for (std::size_t j = 0; j < m; ++j) {
      if (!(p[j] > 0.0 && p[j] < 1.0)) continue;
      const double z = normal_quantile(p[j]);
      const double density = std::exp(-0.5 * z * z) / 2.5066282746310002;
      const double w = props[j].n * density * density / (p[j] * (1 - p[j]));  // 1 / var of the probit
      const double aj = axis(x[j]);
      sw += w, sa += w * aj, sz += w * z, saa += w * aj * aj, saz += w * aj * z;
      ++inside;
    }
    const double slope = inside >= 3 ? (sw * saz - sa * sz) / (sw * saa - sa * sa) : 0.0;
    const bool fitted = slope > 0.0 && std::isfinite(slope);
    if (fitted) a = std::clamp(((zt - (sz - slope * sa) / sw) / slope), a0, a1);
    r.reached = r.bracketed = true;
    r.value = (sqrt_x ? a * a : a) * (x[i] < 0 ? -1.0 : 1.0);
    r.lo_x = x[i - 1];
    r.hi_x = x[i];
    r.note = fitted ? "fitted to the " + std::to_string(inside) + " values inside the transition, between " +
                          text_4g(x[i - 1]) + " and " + text_4g(x[i])
                    : "interpolated between " + text_4g(x[i - 1]) + " and " + text_4g(x[i]);
    return r;
  }
  r.note = "not reached by " + text_4g(x[m - 1]) + " (there " + text_4g(100 * p[m - 1]) + " %)";
  return r;
}

}  // namespace nimble::detection_power
