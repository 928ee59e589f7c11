// The discrepancy workflow (ident/discrepancy.h), part: the open world. When no library effect
// earns its name, generic terms in the grammar of core/term_expression.h are searched under the
// same entry rules and the same family-wise bound (term_families, term_search); and the signature
// that tells the library's pure delay from a first-order lag (delay_lag_signature).

#include "ident/discrepancy_parts.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "ident/identify.h"

namespace nimble::ident::discrepancy_parts {

namespace {

/// `n` points from `lo` to `hi`, evenly spaced on a log scale.
std::vector<double> log_grid(double lo, double hi, std::size_t n) {
  std::vector<double> out;
  for (std::size_t i = 0; i < n; ++i) {
    const double f = n > 1 ? static_cast<double>(i) / static_cast<double>(n - 1) : 0.0;
    out.push_back(lo * std::pow(hi / lo, f));
  }
  return out;
}

/// A number as an expression's text, three significant digits (the column is computed from the
/// parsed text, so what is reported is what was fitted).
std::string number_text(double x) {
  std::ostringstream o;
  o.precision(3);
  o << x;
  return o.str();
}

TermFamily family(const std::string& label, const std::vector<std::string>& texts) {
  TermFamily f;
  f.label = label;
  for (const auto& t : texts) f.points.push_back(TermExpression::parse(t));
  return f;
}

/// Held-out residual of equation `e` of `m` with `a` appended: each fold predicted by the fit on
/// the others. Empty if a fit is singular.
VectorXd heldout_with(const Model& m, std::size_t e, const Addition& a, const Folds& folds) {
  std::vector<Addition> all = m.added[e];
  all.push_back(a);
  const MatrixXd C = augmented_design(m.eqs[e], all);
  const FoldStats fs = fold_stats(C, m.eqs[e].y, folds);
  VectorXd out(m.eqs[e].y.size());
  for (std::size_t k = 0; k < folds.size(); ++k) {
    VectorXd th;
    if (!solve(fs.Gt - fs.G[k], fs.bt - fs.b[k], th)) return {};
    const auto [lo, hi] = folds[k];
    out.segment(lo, hi - lo) = m.eqs[e].y.segment(lo, hi - lo) - C.middleRows(lo, hi - lo) * th;
  }
  return out;
}

}  // namespace

std::vector<TermFamily> term_families(const UniformData& d, const std::vector<std::string>& inputs) {
  std::vector<std::string> states{"p", "v"};
  std::vector<std::string> ins;
  for (const auto& in : inputs) {
    if (d.has(in) && excited(d.at(in), in)) ins.push_back(in);
  }
  std::vector<std::string> all = states;
  all.insert(all.end(), ins.begin(), ins.end());
  std::vector<TermFamily> out;
  const auto is_input = [&](const std::string& s) { return std::find(ins.begin(), ins.end(), s) != ins.end(); };
  // Powers and odd and even functions of one signal. (Its linear term is in the model, so a
  // one-sided pos(x) and abs(x) span the same: pos(x) reads as "more effective one way" for an
  // input, abs(x) as an even dependence for a state.)
  for (const auto& x : all) {
    out.push_back(family(x + "^2", {x + "^2"}));
    out.push_back(family(x + "^3", {x + "^3"}));
    out.push_back(family(x + "*abs(" + x + ")", {x + "*abs(" + x + ")"}));
    out.push_back(family("sign(" + x + ")", {"sign(" + x + ")"}));
    out.push_back(is_input(x) ? family("pos(" + x + ")", {"pos(" + x + ")"}) : family("abs(" + x + ")", {"abs(" + x + ")"}));
  }
  // Products to degree 3.
  for (std::size_t i = 0; i < all.size(); ++i) {
    for (std::size_t j = i + 1; j < all.size(); ++j) {
      const std::string& x = all[i];
      const std::string& y = all[j];
      out.push_back(family(x + "*" + y, {x + "*" + y}));
      out.push_back(family(x + "^2*" + y, {x + "^2*" + y}));
      out.push_back(family(x + "*" + y + "^2", {x + "*" + y + "^2"}));
      for (std::size_t k = j + 1; k < all.size(); ++k) {
        out.push_back(family(x + "*" + y + "*" + all[k], {x + "*" + y + "*" + all[k]}));
      }
    }
  }
  // An input's dead zone and backlash of width w (scanned from 1 % to 40 % of its largest
  // magnitude), and its first-order lag (time constant scanned from 4 to 100 ms).
  for (const auto& x : ins) {
    const VectorXd& v = d.at(x);
    const double span = v.cwiseAbs().maxCoeff();
    std::vector<std::string> dz, bl, lag;
    for (double w : log_grid(0.01 * span, 0.4 * span, kTermScanPoints)) {
      dz.push_back("deadzone(" + x + ", " + number_text(w) + ")");
      bl.push_back("backlash(" + x + ", " + number_text(w) + ")");
    }
    for (double tau : log_grid(kLagGridS[0], kLagGridS[1], kTermScanPoints)) lag.push_back("lag(" + x + ", " + number_text(tau) + ")");
    out.push_back(family("deadzone(" + x + ", w)", dz));
    out.push_back(family("backlash(" + x + ", w)", bl));
    out.push_back(family("lag(" + x + ", tau)", lag));
  }
  return out;
}

CandidateTrial Workflow::term_trial(const TermFamily& fam, std::size_t eq, const Model& m, const std::vector<FoldStats>& base,
                                    const std::vector<VectorXd>& base_cv, std::size_t round, std::size_t family_count,
                                    std::vector<Addition>& best_adds) const {
  CandidateTrial t;
  t.name = "term";
  t.round = round;
  t.p_critical = p_critical;
  t.equation = m.eqs[eq].name;
  t.expression = fam.label;
  const std::size_t neq = m.eqs.size();
  std::vector<double> rss_before(neq);
  for (std::size_t e = 0; e < neq; ++e) rss_before[e] = full_rss(base[e]);
  std::vector<ScanPoint> points;
  for (std::size_t i = 0; i < fam.points.size(); ++i) {
    ScanPoint pt;
    pt.k = static_cast<Index>(i);
    const Term term{m.eqs[eq].name, fam.points[i], 0.0, ""};
    VectorXd col = term_column(data, term);
    const bool ok = col.allFinite() && excited(col, "");
    pt.adds = {Addition{eq, {term_parameter_name(term)}, {std::move(col)}}};
    pt.touched.assign(neq, false);
    pt.stats.resize(neq);
    if (ok) {
      std::vector<Addition> all = m.added[eq];
      all.push_back(pt.adds.front());
      pt.stats[eq] = fold_stats(augmented_design(m.eqs[eq], all), m.eqs[eq].y, folds);
      pt.touched[eq] = true;
    }
    close_scan_point(pt, rss_before, ok);
    points.push_back(std::move(pt));
  }
  std::size_t best = 0;
  for (std::size_t i = 1; i < points.size(); ++i) {
    if (points[i].rss_rel < points[best].rss_rel) best = i;
  }
  if (!std::isfinite(points[best].rss_rel)) {
    t.available = false;
    t.reason = "its column is not excited or cannot be separated from the model's";
    return t;
  }
  t.expression = fam.points[best].to_string();
  t.scan_points = points.size();
  CandidateSpec spec;
  spec.name = "term";
  spec.scanned = points.size() > 1;
  const ScanPoint& P = points[best];
  std::vector<bool> use_eq(neq, false);
  std::string p_eq;
  const double p_min = significance(spec, m, P, rss_before, points.size(), t, use_eq, p_eq);
  // The family-wise rule: Bonferroni over the scan and over every family tried in every equation.
  t.p_value = std::min(1.0, p_min * static_cast<double>(points.size()) * static_cast<double>(family_count));
  use_eq.assign(neq, false);
  use_eq[eq] = t.p_value <= p_critical;
  if (!p_eq.empty()) t.highpass_p = above_gust_band(m, P, points.size());
  if (!heldout(spec, m, points, best, base, base_cv, use_eq, ChangeProfile{}, t)) {
    t.reason = "a cross-validation fit is singular (the term is not excited in every block)";
    return t;
  }
  judge(t, p_eq);
  if (t.passed) best_adds = P.adds;
  return t;
}

void Workflow::delay_lag_signature(const Model& m, const ScanPoint& P, const std::string& p_eq, CandidateTrial& t) const {
  // A pure delay keeps the input's gain at every frequency; a first-order lag's falls with
  // frequency. Both fit a late response with one column beside the input; the one that predicts
  // held-out data better, by more than kLagSignatureSigmas standard errors of the difference,
  // is the form. Tested in the equation where the delay was most significant.
  const auto e_it = std::find_if(m.eqs.begin(), m.eqs.end(), [&](const Eq& e) { return e.name == p_eq; });
  if (e_it == m.eqs.end() || p_eq == "F" || !data.has("delta_f")) return;
  const std::size_t e = static_cast<std::size_t>(e_it - m.eqs.begin());
  const auto delay_add = std::find_if(P.adds.begin(), P.adds.end(), [&](const Addition& a) { return a.eq == e; });
  if (delay_add == P.adds.end()) return;
  const VectorXd delay_cv = heldout_with(m, e, *delay_add, folds);
  if (delay_cv.size() == 0) return;
  // The lag's time constant: the best full-data fit on the grid.
  const std::vector<double> rss_before{full_rss(model_stats(m, folds)[e])};
  double best_rss = std::numeric_limits<double>::infinity();
  Addition lag_add;
  double tau_best = 0.0;
  for (double tau : log_grid(kLagGridS[0], kLagGridS[1], kTermScanPoints)) {
    const Term term{p_eq, TermExpression::parse("lag(delta_f, " + number_text(tau) + ")"), 0.0, ""};
    Addition a{e, {term_parameter_name(term)}, {term_column(data, term)}};
    std::vector<Addition> all = m.added[e];
    all.push_back(a);
    const FoldStats fs = fold_stats(augmented_design(m.eqs[e], all), m.eqs[e].y, {{0, m.eqs[e].y.size()}});
    const double r = full_rss(fs);
    if (std::isfinite(r) && r < best_rss) {
      best_rss = r;
      lag_add = std::move(a);
      tau_best = tau;
    }
  }
  if (!std::isfinite(best_rss)) return;
  const VectorXd lag_cv = heldout_with(m, e, lag_add, folds);
  if (lag_cv.size() == 0) return;
  double drop = 0.0, se = 0.0;
  heldout_drop({delay_cv}, {lag_cv}, batch, drop, se);
  t.signature["lag_tau_s"] = tau_best;
  t.signature["lag_heldout_drop"] = drop;
  t.signature["lag_heldout_se"] = se;
  if (drop > kLagSignatureSigmas * se) {
    t.signature_holds = false;
    t.signature_note = "a first-order lag of delta_f (tau " + fmt(tau_best) + " s) predicts held-out " + p_eq +
                       " better than the delay of " + fmt(t.delay_s) + " s (by " + fmt(100.0 * drop) + " % +- " +
                       fmt(100.0 * se) + "): the input's gain falls with frequency, which a pure delay's does not";
  }
}

std::vector<std::string> term_search(const Workflow& wf, const std::vector<std::string>& inputs, Model& m,
                                     DiscrepancyResult& res) {
  std::vector<std::string> entered;
  const std::vector<TermFamily> families = term_families(wf.data, inputs);
  std::vector<std::size_t> eqs;  // the roll moment and the side force (not the actuator's own equation)
  for (std::size_t e = 0; e < m.eqs.size(); ++e) {
    if (m.eqs[e].name == "L" || m.eqs[e].name == "Y") eqs.push_back(e);
  }
  const std::size_t family_count = families.size() * eqs.size();
  std::vector<std::pair<std::size_t, std::string>> done;  // (equation, family label) entered
  for (std::size_t round = 1; round <= wf.opt.term_rounds; ++round) {
    const std::vector<FoldStats> base = model_stats(m, wf.folds);
    const std::vector<VectorXd> base_cv = heldout_residuals(m, wf.folds);
    struct Pass {
      CandidateTrial trial;
      std::vector<Addition> adds;
      std::string label;
    };
    std::vector<Pass> passing;
    CandidateTrial closest;  // the smallest p of the round, reported when nothing passes
    closest.p_value = 2.0;
    for (std::size_t e : eqs) {
      for (const TermFamily& fam : families) {
        if (std::find(done.begin(), done.end(), std::make_pair(e, fam.label)) != done.end()) continue;
        std::vector<Addition> adds;
        CandidateTrial t = wf.term_trial(fam, e, m, base, base_cv, round, family_count, adds);
        if (!t.available) continue;
        if (t.passed) {
          passing.push_back({std::move(t), std::move(adds), fam.label});
        } else if (t.p_value < closest.p_value) {
          closest = std::move(t);
        }
      }
    }
    if (passing.empty()) {
      if (closest.p_value <= 1.0) res.candidates.push_back(std::move(closest));
      break;
    }
    std::size_t best = 0;
    for (std::size_t i = 1; i < passing.size(); ++i) {
      if (passing[i].trial.heldout_drop > passing[best].trial.heldout_drop) best = i;
    }
    Pass& win = passing[best];
    // Other forms that explain the same thing (their columns, the model's projected out,
    // correlate by more than the collinearity bound): reported beside the form that entered.
    const Addition& wa = win.adds.front();
    const MatrixXd X = m.X(wa.eq);
    for (std::size_t i = 0; i < passing.size(); ++i) {
      if (i == best || passing[i].adds.front().eq != wa.eq) continue;
      const double rho = std::fabs(residual_correlation(X, wa.cols.front(), passing[i].adds.front().cols.front()));
      if (rho > wf.opt.collinearity) win.trial.alternatives.push_back(passing[i].trial.expression);
    }
    win.trial.entered = true;
    win.trial.reason = "entered: " + win.trial.reason;
    done.emplace_back(wa.eq, win.label);
    Term term{m.eqs[wa.eq].name, TermExpression::parse(win.trial.expression), 0.0, "rig discrepancy"};
    entered.push_back(kTermPrefix + term_parameter_name(term));
    m.effect_names.push_back(entered.back());
    m.found_terms.push_back(std::move(term));
    m.added[wa.eq].push_back(wa);
    for (auto& p : passing) res.candidates.push_back(std::move(p.trial));
  }
  return entered;
}

}  // namespace nimble::ident::discrepancy_parts
