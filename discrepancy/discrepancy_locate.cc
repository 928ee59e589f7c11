// The discrepancy workflow (discrepancy/discrepancy.h), part: where the residual of the baseline
// structure lives: a periodic component, a nonlinear dependence on a state or input, and the
// manoeuvres and windows that carry its energy (descriptive). Every
// test here is an alarm test, held to the one rule of the workflow (ident/README.md "One error
// rate for every alarm").

#include "discrepancy/discrepancy_location.h"
#include "discrepancy/discrepancy_parts.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <memory>

#include "core/chi_square.h"
#include "ident/metrics.h"
#include "ident/spectrum.h"

namespace nimble::ident::discrepancy_parts {

namespace {

/// One orthonormal discrete Laguerre bank of `order` filters with pole a, applied to u.
void laguerre(const VectorXd& u, double a, int order, std::vector<VectorXd>& out) {
  const Index n = u.size();
  VectorXd prev(n);
  const double g = std::sqrt(1.0 - a * a);
  double s = 0.0;
  for (Index i = 0; i < n; ++i) prev[i] = s = a * s + g * u[i];
  out.push_back(prev);
  for (int k = 1; k < order; ++k) {
    VectorXd cur(n);
    double y = 0.0, x_last = 0.0;
    for (Index i = 0; i < n; ++i) {
      y = a * y + x_last - a * prev[i];
      x_last = prev[i];
      cur[i] = y;
    }
    out.push_back(cur);
    prev = std::move(cur);
  }
}

}  // namespace

Excitation excitation_bank(const UniformData& d, const std::vector<std::string>& names) {
  Excitation ex;
  std::vector<VectorXd> cols{VectorXd::Ones(d.size())};
  for (const auto& name : names) {
    if (!d.has(name) || !excited(d.at(name), name)) continue;
    const VectorXd& u = d.at(name);
    const VectorXd c = u.array() - u[0];  // the filters start at rest, as the record does (hover)
    for (double tau : kExcitationTimeConstants) laguerre(c, std::exp(-1.0 / (tau * d.rate_hz)), kExcitationOrder, cols);
    ex.signals.push_back(name);
  }
  if (!ex.signals.empty()) ex.Z = design(cols);
  return ex;
}

Span::Span(const MatrixXd& A) {
  const VectorXd scale = (A.colwise().squaredNorm().transpose()).cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const MatrixXd G = scale.asDiagonal() * (A.transpose() * A) * scale.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<MatrixXd> eig(G);
  const VectorXd& lambda = eig.eigenvalues();
  std::vector<Index> keep;
  for (Index i = 0; i < lambda.size(); ++i) {
    if (lambda[i] > kSpanTolerance * lambda.maxCoeff()) keep.push_back(i);
  }
  MatrixXd T(A.cols(), static_cast<Index>(keep.size()));
  for (std::size_t j = 0; j < keep.size(); ++j) {
    T.col(static_cast<Index>(j)) = scale.asDiagonal() * eig.eigenvectors().col(keep[j]) / std::sqrt(lambda[keep[j]]);
  }
  Q = A * T;
}

LocationFrame::LocationFrame(const MatrixXd& X, const VectorXd& y_in, const MatrixXd& Z)
    : y(y_in), excitation(Z), model_and_excitation([&] {
        MatrixXd W(X.rows(), X.cols() + Z.cols());
        W << X, Z;
        return W;
      }()) {
  residual = model_and_excitation.residualise(y);
  excitation_columns = Z;
}

/// Block length for the batch means of the scores R_i e_i (the columns R, partialled on the
/// frame, times the residual e): twice the lag at which the scores' mean autocorrelation over
/// the columns first falls below 0.1, at least min_block, at most n / kMinScoreBlocks. A test of
/// a regressor against a slowly varying residual needs blocks longer than the residual's
/// correlation times the regressor's, not the residual's alone.
Index score_block(const MatrixXd& R, const VectorXd& e, Index min_block) {
  const Index n = e.size();
  const Index cap = std::max<Index>(1, n / kMinScoreBlocks);
  MatrixXd S(n, R.cols());
  for (Index j = 0; j < R.cols(); ++j) S.col(j) = (R.col(j).array() * e.array()).matrix();
  for (Index j = 0; j < R.cols(); ++j) S.col(j).array() -= S.col(j).mean();
  const VectorXd c0 = S.colwise().squaredNorm().transpose();
  Index lag = 1;
  for (; lag < cap; ++lag) {
    double rho = 0.0;
    for (Index j = 0; j < R.cols(); ++j) {
      if (c0[j] > 0.0) rho += S.col(j).head(n - lag).dot(S.col(j).tail(n - lag)) / c0[j];
    }
    if (std::fabs(rho / static_cast<double>(R.cols())) < 0.1) break;
  }
  return std::clamp<Index>(std::max<Index>(2 * lag, min_block), 1, cap);
}

/// Wald test that the residual of the frame does not depend on the columns C (partialled on the
/// frame's span by Frisch-Waugh-Lovell): batch-means covariance of the partialled scores over
/// score_block() blocks (for these coefficients equal to the full regression's sandwich),
/// Hotelling's T^2 reference (wald_tail). Returns the p-value; `partial_r` the share of the
/// residual's sum of squares the columns explain, square-rooted.
double frame_wald(const LocationFrame& frame, const MatrixXd& C, Index min_block, double* partial_r) {
  const Index n = frame.y.size(), k = C.cols();
  MatrixXd R(n, k);
  for (Index j = 0; j < k; ++j) R.col(j) = frame.model_and_excitation.residualise(C.col(j));
  const ScaledSolver sr(R.transpose() * R);
  if (!sr.ok) return 1.0;
  const VectorXd th = sr.solve(R.transpose() * frame.residual);
  const VectorXd e = frame.residual - R * th;
  const Index block = score_block(R, e, min_block);
  // The partialled regression's sandwich, its degrees of freedom those of the full one (the
  // frame's span and C).
  const double q = static_cast<double>(frame.model_and_excitation.rank() + k);
  const MatrixXd cov =
      coloured_covariance(R, e, block) * (static_cast<double>(n - k) / std::max(1.0, static_cast<double>(n) - q));
  const double wald = th.dot(cov.ldlt().solve(th));
  if (partial_r) {
    const double rss0 = frame.residual.squaredNorm();
    *partial_r = rss0 > 0.0 ? std::sqrt(std::max(0.0, 1.0 - e.squaredNorm() / rss0)) : 0.0;
  }
  return wald_tail(wald, k, block_count(n, block));
}

double instrumented_wald(const MatrixXd& X, const VectorXd& y, const MatrixXd& C, const Span& instruments,
                         Index min_block, double* coefficient, double* sigma) {
  const Index n = y.size(), k = C.cols(), q = X.cols() + k;
  if (instruments.rank() < q) return 1.0;  // fewer instruments than regressors: not identified
  MatrixXd W(n, q);
  W << X, C;
  const MatrixXd& Q = instruments.Q;
  const MatrixXd H = Q * (Q.transpose() * W);  // the regressors' excitation parts
  const ScaledSolver s(H.transpose() * W);
  if (!s.ok) return 1.0;
  const VectorXd theta = s.solve(H.transpose() * y);
  const VectorXd u = y - W * theta;
  const Index block = score_block(H.rightCols(k), u, min_block);
  const MatrixXd cov = coloured_covariance(H, u, block);
  const VectorXd th = theta.tail(k);
  const double wald = th.dot(cov.bottomRightCorner(k, k).ldlt().solve(th));
  if (coefficient) *coefficient = theta[q - 1];
  if (sigma) *sigma = std::sqrt(std::max(0.0, cov(q - 1, q - 1)));
  return wald_tail(wald, k, block_count(n, block));
}

/// The held-out rule every candidate passes, for the columns C on the frame: each of the folds
/// predicted by the frame's span with and without C fitted on the other folds; true when the
/// relative drop of the held-out squared error exceeds `sigmas` of its standard error
/// (heldout_drop(), a Diebold-Mariano comparison).
bool heldout_confirms(const LocationFrame& frame, const MatrixXd& C, const LocationRule& rule) {
  const MatrixXd& Q = frame.model_and_excitation.Q;
  MatrixXd D(Q.rows(), Q.cols() + C.cols());
  D << Q, C;
  const FoldStats base = fold_stats(Q, frame.y, rule.folds), with = fold_stats(D, frame.y, rule.folds);
  VectorXd before(Q.rows()), after(Q.rows());
  for (std::size_t k = 0; k < rule.folds.size(); ++k) {
    const auto [a, b] = rule.folds[k];
    VectorXd t0, t1;
    if (!solve(base.Gt - base.G[k], base.bt - base.b[k], t0) || !solve(with.Gt - with.G[k], with.bt - with.b[k], t1)) {
      return false;
    }
    before.segment(a, b - a) = frame.y.segment(a, b - a) - Q.middleRows(a, b - a) * t0;
    after.segment(a, b - a) = frame.y.segment(a, b - a) - D.middleRows(a, b - a) * t1;
  }
  double drop = 0.0, se = 0.0;
  BatchRule batch;
  batch.min_block = rule.min_block;
  heldout_drop({before}, {after}, batch, drop, se);
  return drop > 0.0 && drop > rule.heldout_sigmas * se;
}

/// A periodic component of the frame's residual (see the declaration).
void frequency_peaks(const LocationFrame& frame, const std::string& output, double scale, double rate, double f_lo,
                     double f_hi, const LocationRule& rule, std::vector<FrequencyFinding>& out) {
  const Index n = frame.y.size();
  const double T = static_cast<double>(n) / rate;
  const double f =
      scan_frequency({frame.residual}, rate, f_lo, f_hi, 1, std::vector<bool>(static_cast<std::size_t>(n), true));
  const double M = std::max(1.0, std::ceil((f_hi - f_lo) * T));  // independent frequencies of the band
  MatrixXd C(n, 2);
  for (Index i = 0; i < n; ++i) {
    const double a = 2.0 * M_PI * f * static_cast<double>(i) / rate;
    C(i, 0) = std::sin(a);
    C(i, 1) = std::cos(a);
  }
  const double p = std::min(1.0, frame_wald(frame, C, rule.min_block, nullptr) * M);
  if (p > rule.alpha || !heldout_confirms(frame, C, rule)) return;
  // The peak against its neighbourhood's median, for the report.
  const Psd P = periodogram(frame.residual / scale, rate);
  const Index k = static_cast<Index>(std::lround(f / P.df_hz));
  std::vector<double> nbh;
  for (Index j = std::max<Index>(0, k - 20); j <= std::min<Index>(P.psd.size() - 1, k + 20); ++j) {
    if (std::abs(j - k) > 2) nbh.push_back(P.psd[j]);
  }
  double ratio = 0.0;
  if (!nbh.empty()) {
    std::nth_element(nbh.begin(), nbh.begin() + static_cast<long>(nbh.size() / 2), nbh.end());
    const double background = nbh[nbh.size() / 2] / std::log(2.0);
    ratio = background > 0.0 ? P.psd[k] / background : 0.0;
  }
  out.push_back({output, f, ratio, p});
}

/// Residual against a nonlinear function of each state and input, seen through the excitation
/// (see the declaration), Bonferroni over the signals tested.
void state_findings(const LocationFrame& frame, const MatrixXd& X, const std::string& output, const UniformData& d,
                    const LocationRule& rule, std::vector<StateFinding>& out) {
  const Index min_block = rule.min_block;
  const double alpha = rule.alpha;
  std::unique_ptr<LocationFrame> high;  // the frame above the gust band, built when first needed
  std::vector<std::string> signals;
  for (const char* s : {"p", "v", "phi", "delta_f", "u", "w", "delta_t"}) {
    if (d.has(s) && excited(d.at(s), s)) signals.push_back(s);
  }
  const double M = static_cast<double>(signals.size());
  const Index n = frame.y.size();
  for (const auto& s : signals) {
    const VectorXd xh = frame.excitation.project(d.at(s));
    const double sd = std::sqrt((xh.array() - xh.mean()).square().mean());
    if (!(sd > 1e-12 * (1.0 + std::fabs(xh.mean())))) continue;
    const VectorXd z = (xh.array() - xh.mean()) / sd;
    MatrixXd C(n, 2);
    C.col(0) = z.array().square().matrix();
    C.col(1) = z.array().cube().matrix();
    double partial_r = 0.0;
    const double p = std::min(1.0, frame_wald(frame, C, min_block, &partial_r) * M);
    if (p > alpha) continue;
    // Above the gust band, as every candidate (DiscrepancyOptions::gust_band_hz): a slow
    // residual (a side wind, a drift of the trim) against a slow function of the excitation is
    // not a nonlinearity of the model.
    if (!high) {
      high = std::make_unique<LocationFrame>(high_pass_columns(X, rule.gust_band_hz, d.rate_hz),
                                             high_pass(frame.y, rule.gust_band_hz, d.rate_hz),
                                             high_pass_columns(frame.excitation_columns, rule.gust_band_hz, d.rate_hz));
    }
    const double p_high =
        std::min(1.0, frame_wald(*high, high_pass_columns(C, rule.gust_band_hz, d.rate_hz), min_block, nullptr) * M);
    if (p_high <= rule.gust_band_alpha && heldout_confirms(frame, C, rule)) out.push_back({output, s, partial_r, p});
  }
}

void time_findings(const std::string& output, const VectorXd& r, const UniformData& d, const Segments& seg,
                   double window_s, std::vector<TimeFinding>& out) {
  const double total = r.squaredNorm();
  const Index n = r.size();
  if (!(total > 0.0) || n == 0) return;
  auto share = [&](Index a, Index b) { return r.segment(a, b - a).squaredNorm() / total; };
  for (const auto& [what, list] :
       {std::pair<std::string, const std::vector<TimeRange>*>{"manoeuvre", &seg.manoeuvre}, {"hover", &seg.hover}}) {
    for (const auto& [a, b] : sample_ranges(d, *list)) {
      out.push_back(
          {output, what, d.t_s[a], d.t_s[b - 1], share(a, b), static_cast<double>(b - a) / static_cast<double>(n)});
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
