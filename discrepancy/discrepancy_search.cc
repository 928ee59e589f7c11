// The discrepancy workflow (discrepancy/discrepancy.h), part: the trials of the stepwise search: a
// candidate with regressors on the current model, scanned, judged by the entry rules and held
// out. The candidates found in the residual's spectrum are in discrepancy_spectral.cc, the
// signatures that confirm a name in discrepancy_signatures.cc.

#include "discrepancy/discrepancy_parts.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <utility>

#include <boost/math/distributions/fisher_f.hpp>

#include "core/chi_square.h"
#include "ident/metrics.h"

namespace nimble::ident::discrepancy_parts {

void close_scan_point(ScanPoint& pt, const std::vector<double>& rss_before, bool ok) {
  for (std::size_t e = 0; e < rss_before.size() && ok; ++e) {
    const double r = pt.touched[e] ? full_rss(pt.stats[e]) : rss_before[e];
    if (!std::isfinite(r)) ok = false;
    pt.rss_rel += r / rss_before[e];
  }
  if (!ok) pt.rss_rel = std::numeric_limits<double>::infinity();
}

std::size_t best_scan_point(const std::vector<ScanPoint>& points) {
  std::size_t best = 0;
  for (std::size_t i = 1; i < points.size(); ++i) {
    if (points[i].rss_rel < points[best].rss_rel) best = i;
  }
  return best;
}

std::vector<double> full_rss_each(const std::vector<FoldStats>& stats) {
  std::vector<double> out;
  for (const auto& f : stats) out.push_back(full_rss(f));
  return out;
}

/// Every scan point of `spec` (one, or one per delay): its columns and the fold statistics
/// of each equation it touches, with its total relative RSS (infinite if it cannot be fitted).
std::vector<ScanPoint> Workflow::scan(const CandidateSpec& spec, const Model& m, const std::vector<Index>& delays,
                                      const std::vector<double>& rss_before) const {
  const std::size_t neq = m.eqs.size();
  const double g = vehicle.gravity_mps2;
  std::vector<ScanPoint> points;
  for (Index k : delays) {
    ScanPoint pt;
    pt.k = k;
    pt.adds = candidate_columns(spec, data, model.trim, g, k);
    pt.touched.assign(neq, false);
    pt.stats.resize(neq);
    bool ok = true;
    for (const auto& a : pt.adds) {
      for (const auto& c : a.cols) {
        const bool constant = spec.constant();
        if (!constant && !excited(c, "")) ok = false;
      }
      std::vector<Addition> all = m.added[a.eq];
      all.push_back(a);
      pt.stats[a.eq] = fold_stats(augmented_design(m.eqs[a.eq], all), m.eqs[a.eq].y, folds);
      pt.touched[a.eq] = true;
    }
    close_scan_point(pt, rss_before, ok);
    points.push_back(std::move(pt));
  }
  return points;
}

/// Significance of the chosen scan point: the Wald test of its terms in each equation with
/// the coloured covariance (Bonferroni over terms and scan points); fills the trial's
/// statistics, the equations it enters (`use_eq`) and the equation of its smallest p
/// (`p_eq`). Returns that p before the Bonferroni factor.
double Workflow::significance(const CandidateSpec& spec, const Model& m, const ScanPoint& P,
                              const std::vector<double>& rss_before, std::size_t scan_points, CandidateTrial& t,
                              std::vector<bool>& use_eq, std::string& p_eq) const {
  double p_min = 1.0;
  // The candidate enters only the equations where its terms are significant on their own
  // (with the same Bonferroni factors): a term that explains nothing in an equation would
  // only add variance there.
  const double bonferroni = static_cast<double>(P.adds.size()) * static_cast<double>(scan_points);
  for (const auto& a : P.adds) {
    AdditionFit f;
    if (!fit_addition(m, a, P.stats[a.eq], rss_before[a.eq], batch, f)) continue;
    if (!P.effective_blocks.empty()) f.p = wald_tail(f.wald, f.k, P.effective_blocks[a.eq]);
    if (P.stationary_floor && f.p * bonferroni <= p_critical) stationary_floor(m, a, batch, f);
    record(m, a, f, t);
    const std::string& eqname = m.eqs[a.eq].name;
    use_eq[a.eq] = f.p * bonferroni <= p_critical;
    if (f.p < p_min) {
      p_min = f.p;
      p_eq = eqname;
    }
    if (spec.signature == effects::Signature::kInflow) t.signature["p_" + eqname] = f.p;
    if (spec.scan == effects::Scan::kDelay) {
      // A delayed input acts (mostly) delayed: with the columns delta_f and
      // delta_f(t - tau) - delta_f the delayed fraction is c / theta_df. In closed loop a
      // feedback-driven correlation of delta_f with the filtered equation error also
      // favours the delayed column, but keeps most of the input instantaneous. (The scan's
      // delay is biased low by the same correlation, which leaves a small instantaneous part
      // with a real delay: the criterion is the fraction, not its significance.)
      const auto it = std::find(m.eqs[a.eq].names.begin(), m.eqs[a.eq].names.end(), delayed_input(eqname));
      if (it != m.eqs[a.eq].names.end()) {
        const Index i = static_cast<Index>(it - m.eqs[a.eq].names.begin());
        const double c = f.theta[f.off];
        const double inst = f.theta[i] - c;
        const double var = f.cov(i, i) + f.cov(f.off, f.off) - 2.0 * f.cov(i, f.off);
        t.instantaneous_f[eqname] = var > 0.0 ? inst * inst / var : std::numeric_limits<double>::infinity();
        t.parameters[delayed_input(eqname) + "_fraction_delayed"] = f.theta[i] != 0.0 ? c / f.theta[i] : 0.0;
      }
    }
  }

  // A time-varying effectiveness (effectiveness_drift, effectiveness_step) is one physical change
  // of the flap input, which acts in roll moment and side force alike: it enters every equation
  // it has a term in once it is significant in one. Left out of the equation where it is weaker,
  // the change there would be named again in the next round as another effect (a drift for what
  // is a step).
  if (spec.change != effects::EffectivenessChange::kNone &&
      std::any_of(use_eq.begin(), use_eq.end(), [](bool b) { return b; })) {
    for (const auto& a : P.adds) use_eq[a.eq] = true;
  }
  return p_min;
}

/// The chosen scan point's smallest Wald p on the equations high-passed above the gust band
/// (y and every column alike), Bonferroni over terms and scan points.
double Workflow::above_gust_band(const Model& m, const ScanPoint& P, std::size_t scan_points) const {
  double p_hp = 1.0;
  for (const auto& a : P.adds) {
    // The model's columns and y high-passed once per round (every candidate of a round has
    // them), the candidate's columns here.
    HighPassed& model_hp = high_passed[a.eq];
    const MatrixXd X = m.X(a.eq);
    if (model_hp.X.cols() != X.cols() || model_hp.X.rows() != X.rows()) {
      model_hp.X = high_pass_columns(X, opt.gust_band_hz, data.rate_hz);
      model_hp.y = high_pass(m.eqs[a.eq].y, opt.gust_band_hz, data.rate_hz);
    }
    MatrixXd C(X.rows(), X.cols() + static_cast<Index>(a.cols.size()));
    C.leftCols(X.cols()) = model_hp.X;
    for (std::size_t j = 0; j < a.cols.size(); ++j) {
      C.col(X.cols() + static_cast<Index>(j)) = high_pass(a.cols[j], opt.gust_band_hz, data.rate_hz);
    }
    const VectorXd& y = model_hp.y;
    VectorXd theta;
    const FoldStats fs = fold_stats(C, y, {{0, C.rows()}});
    if (!solve(fs.Gt, fs.bt, theta)) continue;
    const VectorXd resid = y - C * theta;
    const Index block = batch.block(resid);
    const MatrixXd cov = coloured_covariance(C, resid, block);
    const Index kc = static_cast<Index>(a.cols.size());
    const VectorXd th = theta.tail(kc);
    const double wald = th.dot(cov.bottomRightCorner(kc, kc).ldlt().solve(th));
    p_hp = std::min(p_hp, wald_tail(wald, kc, block_count(C.rows(), block)));
  }
  return std::min(1.0, p_hp * static_cast<double>(P.adds.size()) * static_cast<double>(scan_points));
}

/// The held-out drop of the squared error with the candidate (K-fold; a scanned candidate picks
/// its delay on the training folds, effectiveness_step averages over its change times:
/// heldout_change): every sample predicted by a fit that did not see its block. False if a
/// cross-validation fit is singular.
bool Workflow::heldout(const CandidateSpec& spec, const Model& m, const std::vector<ScanPoint>& points,
                       std::size_t best, const std::vector<FoldStats>& base, const std::vector<VectorXd>& base_cv,
                       const std::vector<bool>& use_eq, const ChangeProfile& profile, CandidateTrial& t) const {
  const std::size_t neq = m.eqs.size();
  const std::size_t K = folds.size();
  std::vector<VectorXd> after = base_cv;
  if (spec.scan == effects::Scan::kChangeTime) {
    if (!heldout_change(spec, m, points, use_eq, profile, after)) return false;
    heldout_drop(base_cv, after, batch, t.heldout_drop, t.heldout_se);
    return true;
  }
  bool cv_ok = true;
  // The designs of each scan point picked, built once (a fold picks one; most pick the same).
  std::map<std::size_t, std::vector<std::pair<Addition, MatrixXd>>> designs;
  for (std::size_t k = 0; k < K && cv_ok; ++k) {
    std::size_t pick = best;
    if (spec.scanned()) {
      double best_rel = std::numeric_limits<double>::infinity();
      for (std::size_t i = 0; i < points.size(); ++i) {
        if (!std::isfinite(points[i].rss_rel)) continue;
        double rel = 0.0;
        for (std::size_t e = 0; e < neq && std::isfinite(rel); ++e) {
          if (!points[i].touched[e]) {
            rel += 1.0;
            continue;
          }
          rel += training_rss(points[i].stats[e], k) / training_rss(base[e], k);
        }
        if (rel < best_rel) {
          best_rel = rel;
          pick = i;
        }
      }
    }
    const auto [a, b] = folds[k];
    auto found = designs.find(pick);
    if (found == designs.end()) {
      std::vector<std::pair<Addition, MatrixXd>> built;
      for (auto& add : columns_of(spec, points[pick])) {
        std::vector<Addition> all = m.added[add.eq];
        all.push_back(add);
        MatrixXd C = augmented_design(m.eqs[add.eq], all);
        built.emplace_back(std::move(add), std::move(C));
      }
      found = designs.emplace(pick, std::move(built)).first;
    }
    for (const auto& [add, C] : found->second) {
      if (!use_eq[add.eq] && std::any_of(use_eq.begin(), use_eq.end(), [](bool b) { return b; })) continue;
      const FoldStats& fs = points[pick].stats[add.eq];
      VectorXd th;
      if (!solve(fs.Gt - fs.G[k], fs.bt - fs.b[k], th)) {
        cv_ok = false;
        break;
      }
      after[add.eq].segment(a, b - a) = m.eqs[add.eq].y.segment(a, b - a) - C.middleRows(a, b - a) * th;
    }
  }
  if (!cv_ok) return false;
  heldout_drop(base_cv, after, batch, t.heldout_drop, t.heldout_se);
  return true;
}

/// Whether the trial passes every entry rule, and its reason in words.
void Workflow::judge(CandidateTrial& t, const std::string& p_eq) const {
  const double heldout_sigmas = opt.heldout_sigmas;
  const bool significant = t.p_value <= p_critical;
  const bool pse_falls = !p_eq.empty() && t.pse_after.at(p_eq) < t.pse_before.at(p_eq);
  const auto frac = t.parameters.find(delayed_input(p_eq) + "_fraction_delayed");
  const bool consistent = frac == t.parameters.end() || frac->second >= 0.5;
  const bool above_gusts = t.highpass_p <= opt.gust_band_alpha;
  const bool heldout = t.heldout_drop > 0.0 && t.heldout_drop > heldout_sigmas * t.heldout_se;
  t.passed = significant && pse_falls && heldout && consistent && above_gusts;
  std::ostringstream why;
  if (t.passed) {
    why << "passes: p " << fmt(t.p_value) << " <= " << fmt(p_critical) << " (F " << fmt(t.partial_f[p_eq]) << " in "
        << p_eq << "), PSE falls, held-out error falls " << fmt(100.0 * t.heldout_drop) << " % (+- "
        << fmt(100.0 * t.heldout_se) << ")";
  } else {
    why << "fails:";
    if (!significant) {
      why << " not significant (p " << fmt(t.p_value) << " > " << fmt(p_critical);
      if (!p_eq.empty()) why << ", F " << fmt(t.partial_f[p_eq]) << " in " << p_eq;
      why << ")";
    }
    if (!pse_falls) why << " PSE does not fall;";
    if (!above_gusts) {
      why << " not significant above the gust band (p " << fmt(t.highpass_p) << " > " << fmt(opt.gust_band_alpha)
          << " on the equations high-passed at " << fmt(opt.gust_band_hz) << " Hz);";
    }
    if (!consistent) {
      why << " most of the input still acts at once (delayed fraction " << fmt(frac->second) << " < 0.5 in " << p_eq
          << "): not a delay;";
    }
    if (!heldout) {
      why << " held-out error change " << fmt(-100.0 * t.heldout_drop) << " % is not a drop beyond "
          << fmt(heldout_sigmas) << " standard errors (" << fmt(100.0 * t.heldout_se) << " %)";
    }
  }
  t.reason = why.str();
}

/// Tries `spec` on model `m` in round `round`; fills the trial and, when it passes, the
/// additions it would make.
CandidateTrial Workflow::trial(const CandidateSpec& spec, const Model& m, const std::vector<FoldStats>& base,
                               const std::vector<VectorXd>& base_cv, std::size_t round,
                               std::vector<Addition>& best_adds) const {
  CandidateTrial t;
  t.name = spec.name;
  t.round = round;
  t.p_critical = p_critical;
  for (const auto& need : spec.needs) {
    if (!data.has(need)) {
      t.available = false;
      t.reason = "the data has no " + need;
      return t;
    }
    if (!excited(data.at(need), need)) {
      t.available = false;
      t.reason = need + " is not excited (standard deviation below " + fmt(excitation_floor(need)) + ")";
      return t;
    }
  }
  const std::size_t neq = m.eqs.size();
  std::vector<Index> delays{0};  // the scan: delays [samples] of actuator_delay, change samples of effectiveness_step
  const bool change = spec.scan == effects::Scan::kChangeTime;
  if (spec.scan == effects::Scan::kDelay) {
    delays.clear();
    const Index kmax = std::max<Index>(1, static_cast<Index>(std::floor(opt.delay_max_s * data.rate_hz + 1e-9)));
    for (Index k = 1; k <= kmax; ++k) delays.push_back(k);
  } else if (change) {
    delays = change_grid(data, folds);
  }
  t.scan_points = delays.size();

  const std::vector<double> rss_before = full_rss_each(base);
  const std::vector<ScanPoint> points =
      change ? scan_change(spec, m, delays, base, rss_before) : scan(spec, m, delays, rss_before);
  const std::size_t best = best_scan_point(points);
  if (!std::isfinite(points[best].rss_rel)) {
    t.available = false;
    t.reason = "its regressors are not excited or cannot be separated from the model's";
    return t;
  }
  ScanPoint P = points[best];
  P.adds = columns_of(spec, P);
  ChangeProfile profile;
  if (change) {
    profile = change_profile(m, P);
    P.effective_blocks = profile.kish;
  }
  if (spec.scan == effects::Scan::kDelay) t.delay_s = static_cast<double>(delays[best]) / data.rate_hz;

  std::vector<bool> use_eq(neq, false);
  std::string p_eq;
  const double p_min = significance(spec, m, P, rss_before, delays.size(), t, use_eq, p_eq);
  if (spec.scan == effects::Scan::kDelay) t.parameters[spec.scan_parameter()] = t.delay_s;
  if (change) {
    profile.restrict_to(use_eq);
    t.parameters["t_change_s"] = data.t_s[P.k];
    change_interval(m, points, best, profile, t);
  }

  // Confirmation above the gust band: an unmeasured side wind acts through v - v_g and
  // drives v itself, so in closed loop it correlates the equation error with functions of
  // v (v|v| above all). Its power lies at low frequency; an effect that is a function of the
  // states holds at every frequency. The candidate must stay significant, at
  // opt.gust_band_alpha with the same Bonferroni factors, on the equations high-passed above
  // opt.gust_band_hz (y and every column alike). A constant (sensor_bias) has no content
  // there and is exempt.
  if (!p_eq.empty() && !spec.constant()) t.highpass_p = above_gust_band(m, P, delays.size());
  t.p_value = std::min(1.0, p_min * static_cast<double>(P.adds.size()) * static_cast<double>(delays.size()));
  if (!heldout(spec, m, points, best, base, base_cv, use_eq, profile, t)) {
    t.reason = "a cross-validation fit is singular (the candidate is not excited in every block)";
    return t;
  }
  judge(t, p_eq);
  // The rest of the effect's signature (discrepancy_signatures.cc).
  if (opt.signature_checks && t.passed) signature(spec, m, P, t);
  if (t.passed) {
    for (const auto& a : P.adds) {
      if (use_eq[a.eq]) best_adds.push_back(a);
    }
  }
  return t;
}

}  // namespace nimble::ident::discrepancy_parts
