// The discrepancy workflow (discrepancy/discrepancy.h), part: the candidates whose effect changes during
// the record. effectiveness_drift, (t - t_mid) delta_f, is an ordinary candidate with one column
// per equation; here only its rate is derived when it is named. effectiveness_step,
// H(t - t*) delta_f, is scanned over t*: its fold statistics at every t* of the grid come from
// prefix sums over the samples (the column is delta_f from t* on, so its cross-products with the
// model's columns are sums over the samples after t*), and its change time is named with an
// interval from the profile of the residual sum of squares over t*.

#include "discrepancy/discrepancy_parts.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include <boost/math/distributions/students_t.hpp>

namespace nimble::ident::discrepancy_parts {

namespace {

/// Cumulative sums over the samples of the products of delta_f with the columns of X, with itself
/// and with y: row i holds the sums over samples 0 .. i - 1.
struct ChangePrefix {
  MatrixXd xz;
  VectorXd zz, zy;

  ChangePrefix(const MatrixXd& X, const VectorXd& y, const VectorXd& z) {
    const Index n = X.rows(), q = X.cols();
    xz = MatrixXd::Zero(n + 1, q);
    zz = VectorXd::Zero(n + 1);
    zy = VectorXd::Zero(n + 1);
    for (Index j = 0; j < q; ++j) {
      double s = 0.0;
      for (Index i = 0; i < n; ++i) xz(i + 1, j) = (s += X(i, j) * z[i]);
    }
    double a = 0.0, b = 0.0;
    for (Index i = 0; i < n; ++i) {
      zz[i + 1] = (a += z[i] * z[i]);
      zy[i + 1] = (b += z[i] * y[i]);
    }
  }
};

/// The fold statistics of the design [X, H(t - t*) z] from those of X (`base`) and the prefix
/// sums, the change at sample k.
FoldStats change_stats(const FoldStats& base, const ChangePrefix& P, const Folds& folds, Index k) {
  const Index q = base.Gt.cols();
  FoldStats fs;
  fs.Gt = MatrixXd::Zero(q + 1, q + 1);
  fs.bt = VectorXd::Zero(q + 1);
  fs.st = base.st;
  for (std::size_t f = 0; f < folds.size(); ++f) {
    const auto [a, b] = folds[f];
    const Index lo = std::clamp(k, a, b);
    MatrixXd G(q + 1, q + 1);
    G.topLeftCorner(q, q) = base.G[f];
    const VectorXd g = (P.xz.row(b) - P.xz.row(lo)).transpose();
    G.topRightCorner(q, 1) = g;
    G.bottomLeftCorner(1, q) = g.transpose();
    G(q, q) = P.zz[b] - P.zz[lo];
    VectorXd bv(q + 1);
    bv.head(q) = base.b[f];
    bv[q] = P.zy[b] - P.zy[lo];
    fs.Gt += G;
    fs.bt += bv;
    fs.G.push_back(std::move(G));
    fs.b.push_back(std::move(bv));
    fs.s.push_back(base.s[f]);
  }
  return fs;
}

/// Full-data fit of equation e of `m`: parameters, coloured covariance and the number of blocks it
/// was batched over; false if singular.
bool fit_equation(const Model& m, std::size_t e, const BatchRule& batch, VectorXd& theta, MatrixXd& cov,
                  double& blocks) {
  const MatrixXd C = m.X(e);
  const FoldStats fs = fold_stats(C, m.eqs[e].y, {{0, C.rows()}});
  if (!solve(fs.Gt, fs.bt, theta)) return false;
  const VectorXd r = m.eqs[e].y - C * theta;
  const Index block = batch.block(r);
  cov = coloured_covariance(C, r, block);
  blocks = block_count(C.rows(), block);
  return true;
}

/// The ratio scale * theta[a] / theta[b] with its delta-method standard deviation and 95 % interval
/// (Student t with the batch means' blocks - 1 degrees of freedom), as `key`, `key`_lo, `key`_hi.
void ratio_with_interval(const VectorXd& theta, const MatrixXd& cov, Index a, Index b, double scale, double blocks,
                         const std::string& key, NamedEffect& eff) {
  const double num = theta[a], den = theta[b];
  if (den == 0.0) return;
  const double r = scale * num / den;
  const double ga = scale / den, gb = -scale * num / (den * den);
  const double var = ga * ga * cov(a, a) + gb * gb * cov(b, b) + 2.0 * ga * gb * cov(a, b);
  const double sd = std::sqrt(std::max(0.0, var));
  const double tq = boost::math::quantile(boost::math::students_t(std::max(1.0, blocks - 1.0)), 0.975);
  eff.parameters[key] = r;
  eff.parameters[key + "_lo"] = r - tq * sd;
  eff.parameters[key + "_hi"] = r + tq * sd;
  eff.sigma[key] = sd;
}

}  // namespace

std::vector<Index> change_grid(const UniformData& d, const Folds& folds) {
  std::vector<Index> grid;
  const Index first = folds.front().second, last = folds.back().first;
  const Index step = std::max<Index>(1, std::lround(kChangeGridS * d.rate_hz));
  for (Index k = first; k <= last; k += step) grid.push_back(k);
  if (grid.empty()) grid.push_back((first + last) / 2);
  return grid;
}

std::vector<ScanPoint> Workflow::scan_change(const CandidateSpec& spec, const Model& m, const std::vector<Index>& grid,
                                             const std::vector<FoldStats>& base,
                                             const std::vector<double>& rss_before) const {
  const std::size_t neq = m.eqs.size();
  std::vector<Addition> proto = candidate_columns(spec, data, model.trim, vehicle.gravity_mps2, 0);
  std::vector<std::unique_ptr<ChangePrefix>> prefix(neq);
  for (auto& a : proto) {
    prefix[a.eq] = std::make_unique<ChangePrefix>(m.X(a.eq), m.eqs[a.eq].y, a.cols.front());
    a.cols.clear();  // regenerated for the scan points that need them (columns_of)
  }
  std::vector<ScanPoint> points;
  points.reserve(grid.size());
  for (Index k : grid) {
    ScanPoint pt;
    pt.k = k;
    pt.adds = proto;
    pt.touched.assign(neq, false);
    pt.stats.resize(neq);
    bool ok = true;
    for (const auto& a : proto) {
      pt.stats[a.eq] = change_stats(base[a.eq], *prefix[a.eq], folds, k);
      pt.touched[a.eq] = true;
      const double z2 = pt.stats[a.eq].Gt.bottomRightCorner(1, 1)(0, 0);
      if (!(z2 > 0.0)) ok = false;
    }
    close_scan_point(pt, rss_before, ok);
    points.push_back(std::move(pt));
  }
  return points;
}

std::vector<Addition> Workflow::columns_of(const CandidateSpec& spec, const ScanPoint& pt) const {
  if (pt.adds.empty() || !pt.adds.front().cols.empty()) return pt.adds;
  return candidate_columns(spec, data, model.trim, vehicle.gravity_mps2, pt.k);
}

ChangeProfile Workflow::change_profile(const Model& m, const ScanPoint& P) const {
  // Per equation, from the fit at the best t*: s2, the residual variance, and kappa, the ratio of
  // the change coefficient's coloured to white variance (at least 1), so that the profile
  // statistic allows coloured residuals as the Wald test does; and the effective number of blocks
  // of that coloured variance (change_blocks in discrepancy_parts.h).
  ChangeProfile out;
  out.scale.assign(m.eqs.size(), 0.0);
  out.kish.assign(m.eqs.size(), 0.0);
  out.blocks.assign(m.eqs.size(), 0.0);
  for (const auto& a : P.adds) {
    std::vector<Addition> all = m.added[a.eq];
    all.push_back(a);
    const MatrixXd C = augmented_design(m.eqs[a.eq], all);
    const Index q = C.cols();
    const FoldStats& fs = P.stats[a.eq];
    VectorXd theta, g, unit = VectorXd::Zero(q);
    unit[q - 1] = 1.0;
    if (!solve(fs.Gt, fs.bt, theta) || !solve(fs.Gt, unit, g)) continue;
    const VectorXd r = m.eqs[a.eq].y - C * theta;
    const Index block = batch.block(r);
    const VectorXd w = C * g;  // the change coefficient's influence on each sample
    double coloured = 0.0, sum = 0.0, sum2 = 0.0;
    for (Index i = 0; i < w.size(); i += block) {
      const Index len = std::min(block, w.size() - i);
      const double score = w.segment(i, len).dot(r.segment(i, len));
      const double energy = w.segment(i, len).squaredNorm();
      coloured += score * score;
      sum += energy;
      sum2 += energy * energy;
    }
    // As coloured_covariance: batch means of the scores, times n / (n - q).
    coloured *= static_cast<double>(C.rows()) / static_cast<double>(std::max<Index>(1, C.rows() - q));
    const double s2 = r.squaredNorm() / static_cast<double>(std::max<Index>(1, C.rows() - q));
    const double white = s2 * g[q - 1];
    if (!(s2 > 0.0) || !(white > 0.0)) continue;
    out.scale[a.eq] = 1.0 / (s2 * std::max(1.0, coloured / white));
    out.kish[a.eq] = sum2 > 0.0 ? sum * sum / sum2 : 0.0;
    out.blocks[a.eq] = block_count(C.rows(), block);
  }
  return out;
}

void ChangeProfile::restrict_to(const std::vector<bool>& use_eq) {
  if (!std::any_of(use_eq.begin(), use_eq.end(), [](bool b) { return b; })) return;
  for (std::size_t e = 0; e < scale.size(); ++e) {
    if (!use_eq[e]) scale[e] = 0.0;
  }
}

double ChangeProfile::min_blocks() const {
  double b = std::numeric_limits<double>::infinity();
  for (std::size_t e = 0; e < scale.size(); ++e) {
    if (scale[e] > 0.0) b = std::min(b, blocks[e]);
  }
  return std::isfinite(b) ? b : 0.0;
}

void Workflow::change_interval(const Model& m, const std::vector<ScanPoint>& points, std::size_t best,
                               const ChangeProfile& profile, CandidateTrial& t) const {
  // Profile likelihood of t*: with the other parameters refit at every t*, the statistic
  //   D(t*) = sum over the equations the change enters of (RSS_e(t*) - RSS_e(best)) / (s2_e kappa_e)
  // (change_profile) is the likelihood ratio of t*. A change point is not a regular parameter:
  // D at the true t* is not chi2_1. Near it the log-likelihood ratio is a two-sided random walk
  // with drift (Hinkley 1970); in the Brownian limit the maximum on each side, M, has
  // P(M > x) = exp(-x), independently on the two sides, so P(D_true <= c) = (1 - exp(-c / 2))^2
  // and the 95 % interval is the set of t* with D <= -2 ln(1 - sqrt(0.95)) = 7.35 (chi2_1 would
  // give 3.84 and undercover). It is evaluated on the grid: a change between two grid points is
  // fitted by either, so the interval reaches to the grid points next to the outermost ones
  // accepted (measured: a rig change 9 ms outside half a spacing). The coverage is measured on
  // generated and rig records (tests/ident/test_discrepancy.cc, test_discrepancy_rig.cc).
  if (profile.min_blocks() <= 0.0) return;
  const ScanPoint& P = points[best];
  const double crit = -2.0 * std::log(1.0 - std::sqrt(0.95));
  const double spacing = kChangeGridS;
  double lo = data.t_s[P.k], hi = data.t_s[P.k];
  for (const auto& pt : points) {
    if (!std::isfinite(pt.rss_rel)) continue;
    double D = 0.0;
    for (std::size_t e = 0; e < m.eqs.size(); ++e) {
      if (profile.scale[e] > 0.0) D += (full_rss(pt.stats[e]) - full_rss(P.stats[e])) * profile.scale[e];
    }
    if (D > crit) continue;
    lo = std::min(lo, data.t_s[pt.k]);
    hi = std::max(hi, data.t_s[pt.k]);
  }
  t.parameters["t_change_lo_s"] = std::max(data.t_s[0], lo - spacing);
  t.parameters["t_change_hi_s"] = std::min(data.t_s[data.size() - 1], hi + spacing);
}

bool Workflow::heldout_change(const CandidateSpec& spec, const Model& m, const std::vector<ScanPoint>& points,
                              const std::vector<bool>& use_eq, const ChangeProfile& profile,
                              std::vector<VectorXd>& after) const {
  // Where the training blocks cannot place the change (the held-out block holds the only
  // excitation near it, or delta_f is quiet between two manoeuvres), several t* fit them alike,
  // and picking one (the first, say) would predict the held-out block as if the change were
  // known there. Each held-out block is predicted by the average over t* of the predictions of
  // the fits at t*, weighted by exp(-D_k(t*) / 2), D_k the profile statistic of change_interval
  // on the training blocks (the posterior of t* under a flat prior over the grid): a t* the
  // training blocks rule out weighs nothing, t* they cannot tell apart weigh alike. The
  // prediction is linear in the parameters: the model's columns times the weighted mean of
  // their coefficients, plus delta_f times the weighted sum of the change coefficients of the
  // t* at or before each sample.
  const std::vector<Addition> proto = columns_of(spec, points.front());
  const bool any = std::any_of(use_eq.begin(), use_eq.end(), [](bool b) { return b; });
  std::vector<std::size_t> eqs;
  for (const auto& a : proto) {
    if (!any || use_eq[a.eq]) eqs.push_back(a.eq);
  }
  const VectorXd& df = data.at("delta_f");
  const double cutoff = 2.0 * std::log(1e6);  // weights below 1e-6 of the largest are left out
  std::vector<MatrixXd> X(m.eqs.size());
  for (std::size_t e : eqs) X[e] = m.X(e);
  for (std::size_t k = 0; k < folds.size(); ++k) {
    const auto [a, b] = folds[k];
    std::vector<double> D(points.size(), std::numeric_limits<double>::infinity());
    std::vector<std::vector<VectorXd>> theta(points.size(), std::vector<VectorXd>(m.eqs.size()));
    double d_min = std::numeric_limits<double>::infinity();
    for (std::size_t j = 0; j < points.size(); ++j) {
      if (!std::isfinite(points[j].rss_rel)) continue;
      double Dj = 0.0;
      for (std::size_t e : eqs) {
        const FoldStats& fs = points[j].stats[e];
        const VectorXd bk = fs.bt - fs.b[k];
        if (!solve(fs.Gt - fs.G[k], bk, theta[j][e])) {
          Dj = std::numeric_limits<double>::infinity();
          break;
        }
        Dj += profile.scale[e] * ((fs.st - fs.s[k]) - theta[j][e].dot(bk));
      }
      D[j] = Dj;
      d_min = std::min(d_min, Dj);
    }
    if (!std::isfinite(d_min)) return false;
    for (std::size_t e : eqs) {
      const Index q = X[e].cols();
      VectorXd mean = VectorXd::Zero(q), step = VectorXd::Zero(b - a + 1);
      double wsum = 0.0;
      for (std::size_t j = 0; j < points.size(); ++j) {
        if (!(D[j] - d_min <= cutoff)) continue;
        const double w = std::exp(-0.5 * (D[j] - d_min));
        mean += w * theta[j][e].head(q);
        step[std::clamp(points[j].k, a, b) - a] += w * theta[j][e][q];
        wsum += w;
      }
      VectorXd pred = X[e].middleRows(a, b - a) * mean;
      double c = 0.0;
      for (Index i = a; i < b; ++i) pred[i - a] += (c += step[i - a]) * df[i];
      after[e].segment(a, b - a) = m.eqs[e].y.segment(a, b - a) - pred / wsum;
    }
  }
  return true;
}

void time_varying_parameters(const Model& m, const BatchRule& batch, const UniformData& d, const CandidateTrial& t,
                             NamedEffect& eff) {
  const CandidateSpec* spec = effects::find_definition(t.name);
  const auto change = spec ? spec->change : effects::EffectivenessChange::kNone;
  const bool drift = change == effects::EffectivenessChange::kDrift,
             step = change == effects::EffectivenessChange::kStep;
  if (!drift && !step) return;
  const std::string suffix = drift ? "_df_rate" : "_df_step";
  // The rate (the fraction) from the roll equation when the effect entered it, else from the
  // side-force equation: relative to L_df (Y_df), the model's value at t_mid (before t*).
  for (const char* eq : {"L", "Y"}) {
    for (std::size_t e = 0; e < m.eqs.size(); ++e) {
      if (m.eqs[e].name != eq) continue;
      const auto names = m.names(e);
      const auto ia = std::find(names.begin(), names.end(), std::string(eq) + suffix);
      const auto ib = std::find(names.begin(), names.end(), std::string(eq) + "_df");
      if (ia == names.end() || ib == names.end()) continue;
      VectorXd theta;
      MatrixXd cov;
      double blocks = 0.0;
      if (!fit_equation(m, e, batch, theta, cov, blocks)) continue;
      ratio_with_interval(theta, cov, ia - names.begin(), ib - names.begin(), drift ? 60.0 : 1.0, blocks,
                          drift ? "rate_per_min" : "fraction", eff);
      break;
    }
    if (eff.parameters.count(drift ? "rate_per_min" : "fraction")) break;
  }
  if (drift) {
    eff.parameters["t_mid_s"] = 0.5 * (d.t_s[0] + d.t_s[d.size() - 1]);
  } else {
    for (const char* key : {"t_change_s", "t_change_lo_s", "t_change_hi_s"}) {
      const auto it = t.parameters.find(key);
      if (it != t.parameters.end()) eff.parameters[key] = it->second;
    }
  }
}

}  // namespace nimble::ident::discrepancy_parts
