// The discrepancy workflow (ident/discrepancy.h), part: where the residual of the baseline structure lives: frequency peaks, nonlinear
// dependence on a state or input, and the manoeuvres and windows that carry its energy.

#include "ident/discrepancy_parts.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "core/chi_square.h"
#include "ident/metrics.h"
#include "ident/spectrum.h"

namespace nimble::ident::discrepancy_parts {

// ---------------------------------------------------------------------------------------
// Location.

/// Periodogram peaks of `r` against the median of their neighbourhood (+-20 bins, the
/// centre +-2 bins left out). For a Gaussian process a periodogram ordinate over its
/// spectrum is Exp(1) (chi2_2 / 2) and the local median estimates ln 2 times the
/// spectrum, so P(ratio > x) = exp(-x); the p-value is multiplied by the number of bins
/// scanned (Bonferroni).
void frequency_peaks(const std::string& output, const VectorXd& r, double rate, double f_lo, double f_hi,
                     double alpha, std::vector<FrequencyFinding>& out) {
  const Psd P = periodogram(r, rate);
  const Index nb = P.psd.size();
  const Index half = 20, gap = 2;
  std::vector<Index> bins;
  for (Index k = half; k + half < nb; ++k) {
    if (P.f_hz[k] >= f_lo && P.f_hz[k] <= f_hi) bins.push_back(k);
  }
  if (bins.empty()) return;
  const double M = static_cast<double>(bins.size());
  std::vector<double> nbh;
  FrequencyFinding best;
  bool found = false;
  for (Index k : bins) {
    nbh.clear();
    for (Index j = k - half; j <= k + half; ++j) {
      if (std::abs(j - k) > gap) nbh.push_back(P.psd[j]);
    }
    std::nth_element(nbh.begin(), nbh.begin() + static_cast<long>(nbh.size() / 2), nbh.end());
    const double background = nbh[nbh.size() / 2] / std::log(2.0);
    if (!(background > 0.0)) continue;
    const double ratio = P.psd[k] / background;
    const double p = std::min(1.0, std::exp(-ratio) * M);
    if (p <= alpha && (!found || ratio > best.ratio)) {
      best = {output, P.f_hz[k], ratio, p};
      found = true;
    }
  }
  if (found) out.push_back(best);
}

/// Residual against a nonlinear function of each state and input (x^2 and x^3, which the
/// linear model cannot produce), with the model's regressors: Wald test with the coloured
/// covariance, significant at alpha / (number of signals tested), per equation.
void state_findings(const Model& m, std::size_t e, const UniformData& d, const BatchRule& batch, double alpha,
                    std::vector<StateFinding>& out) {
  std::vector<std::string> signals;
  for (const char* s : {"p", "v", "phi", "delta_f", "u", "w", "delta_t"}) {
    if (d.has(s) && excited(d.at(s), s)) signals.push_back(s);
  }
  const double M = static_cast<double>(signals.size());
  const MatrixXd X = m.X(e);
  VectorXd th0;
  if (!solve(X.transpose() * X, X.transpose() * m.eqs[e].y, th0)) return;
  const double rss0 = (m.eqs[e].y - X * th0).squaredNorm();
  for (const auto& s : signals) {
    const VectorXd& x = d.at(s);
    const double sd = std::sqrt((x.array() - x.mean()).square().mean());
    const VectorXd z = (x.array() - x.mean()) / sd;
    MatrixXd C(X.rows(), X.cols() + 2);
    C << X, z.array().square().matrix(), z.array().cube().matrix();
    VectorXd th;
    if (!solve(C.transpose() * C, C.transpose() * m.eqs[e].y, th)) continue;
    const VectorXd r = m.eqs[e].y - C * th;
    const Index block = batch.block(r);
    const MatrixXd cov = coloured_covariance(C, r, block);
    const VectorXd t2 = th.tail(2);
    const double wald = t2.dot(cov.bottomRightCorner(2, 2).ldlt().solve(t2));
    const double p = std::min(1.0, wald_tail(wald, 2, block_count(C.rows(), block)) * M);
    if (p <= alpha) {
      StateFinding f;
      f.output = m.eqs[e].output;
      f.signal = s;
      f.partial_r = std::sqrt(std::max(0.0, 1.0 - r.squaredNorm() / rss0));
      f.p_value = p;
      out.push_back(f);
    }
  }
}

void time_findings(const std::string& output, const VectorXd& r, const UniformData& d, const Segments& seg,
                   double window_s, std::vector<TimeFinding>& out) {
  const double total = r.squaredNorm();
  const Index n = r.size();
  if (!(total > 0.0) || n == 0) return;
  auto share = [&](Index a, Index b) { return r.segment(a, b - a).squaredNorm() / total; };
  for (const auto& [what, list] : {std::pair<std::string, const std::vector<TimeRange>*>{"manoeuvre", &seg.manoeuvre},
                                   {"hover", &seg.hover}}) {
    for (const auto& [a, b] : sample_ranges(d, *list)) {
      out.push_back({output, what, d.t_s[a], d.t_s[b - 1], share(a, b),
                     static_cast<double>(b - a) / static_cast<double>(n)});
    }
  }
  // The three 1 s windows with the most residual energy.
  const Index w = std::max<Index>(1, static_cast<Index>(std::lround(window_s * d.rate_hz)));
  std::vector<std::pair<double, Index>> windows;
  for (Index a = 0; a + w <= n; a += w) windows.push_back({share(a, a + w), a});
  std::sort(windows.begin(), windows.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
  for (std::size_t i = 0; i < std::min<std::size_t>(3, windows.size()); ++i) {
    const Index a = windows[i].second;
    out.push_back({output, "window", d.t_s[a], d.t_s[a + w - 1], windows[i].first,
                   static_cast<double>(w) / static_cast<double>(n)});
  }
}

}  // namespace nimble::ident::discrepancy_parts
