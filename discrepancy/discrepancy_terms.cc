// The discrepancy workflow (discrepancy/discrepancy.h), part: the open world. When no library effect
// earns its name, generic terms in the grammar of core/term_expression.h are searched under the
// same entry rules and the same family-wise bound (term_families, term_search); and the signature
// every library effect shares, that no generic term's form fits the data better than its own
// (rival_form_signature), which tells the library's pure delay from a first-order lag.

#include "discrepancy/discrepancy_location.h"
#include "discrepancy/discrepancy_parts.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
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

/// A scanned family op(x, v) over `values`, labelled "op(x, parameter)".
TermFamily scanned(const std::string& op, const std::string& x, const std::string& parameter,
                   const std::vector<double>& values) {
  TermFamily f;
  f.label = op + "(" + x + ", " + parameter + ")";
  f.parameter = parameter;
  f.prefix = op + "(" + x + ", ";
  for (double v : values) {
    f.points.push_back(TermExpression::parse(f.prefix + number_text(v) + ")"));
    f.values.push_back(v);
  }
  return f;
}

/// A family of one expression, labelled by it.
TermFamily single(const std::string& text) { return family(text, {text}); }

/// What would tell a library effect from a generic form that fits a record as well.
std::string tell_apart(const std::string& rival, const CandidateSpec& effect) {
  if (rival.rfind("lag(", 0) == 0 && effect.scan == effects::Scan::kDelay) {
    return "a pure delay keeps the input's gain at every frequency, a first-order lag's falls above 1 / (2 pi tau): a "
           "flap input with more power above that frequency (faster doublets, a chirp) tells them apart";
  }
  return "a manoeuvre that moves the signals of " + rival + " and of " + effect.name +
         "'s terms differently (other amplitudes, both signs, other frequencies) tells them apart";
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
  // one-sided pos(x) and abs(x) = sign(x) x span the same: pos(x) reads as "more effective one
  // way" for an input, abs(x) as an even dependence for a state.) Not sign(x) alone: a column
  // that switches with the noise of a signal near zero fits a constant and high-frequency
  // leftovers (measured: sign(p) entered beside a sensor bias and a flapping forcing).
  for (const auto& x : all) {
    out.push_back(single(x + "^2"));
    out.push_back(single(x + "^3"));
    out.push_back(single(x + "*abs(" + x + ")"));
    out.push_back(single((is_input(x) ? "pos(" : "abs(") + x + ")"));
  }
  // Products to degree 3.
  for (std::size_t i = 0; i < all.size(); ++i) {
    for (std::size_t j = i + 1; j < all.size(); ++j) {
      const std::string& x = all[i];
      const std::string& y = all[j];
      out.push_back(single(x + "*" + y));
      out.push_back(single(x + "^2*" + y));
      out.push_back(single(x + "*" + y + "^2"));
      for (std::size_t k = j + 1; k < all.size(); ++k) out.push_back(single(x + "*" + y + "*" + all[k]));
    }
  }
  // A magnitude times an input: an input whose effectiveness changes with the size of a state
  // (L_df delta_f (1 - c |p|): a flap that loses effect at high roll rate).
  for (const char* s : {"p", "v"}) {
    for (const auto& x : ins) out.push_back(single(std::string("abs(") + s + ")*" + x));
  }
  // Linear terms of the recorded signals the equations lack (the model's are p, v and its
  // inputs): a missing derivative such as a roll stiffness L_phi phi. A linear function of a
  // signal's excitation part lies in the excitation's own span, which the confirmation through
  // the excitation projects out, so, as a lag, it is exempt from it.
  for (const auto& x : term_signal_names()) {
    if (x == "p" || x == "v" || std::find(inputs.begin(), inputs.end(), x) != inputs.end()) continue;
    if (!d.has(x) || !excited(d.at(x), x)) continue;
    out.push_back(single(x));
    out.back().linear = true;
    out.back().instrumented = true;
  }
  // An input's dead zone and backlash of width w (scanned from 1 % to 40 % of its largest
  // magnitude), its saturation at s (25 % to 95 %: below, the input would act mostly as its
  // sign), its rate limit r (10 % to 100 % of its largest rate on the record, which the 9 Hz
  // low-pass lowers: a limit of the raw input near its raw largest rate still acts on the fast
  // peaks; one far below turns the input into a ramp) and its first-order lag (time constant
  // scanned from 4 to 100 ms).
  for (const auto& x : ins) {
    const VectorXd& v = d.at(x);
    const double span = v.cwiseAbs().maxCoeff();
    double rate = 0.0;
    for (Index i = 1; i < v.size(); ++i) rate = std::max(rate, std::fabs(v[i] - v[i - 1]) * d.rate_hz);
    // Each acts through the input. A lag is a linear filter, and a rate limit acts where the input
    // moves fastest, which its excitation part (a projection on the excitation's slow bank) does
    // not reach: both are exempt from that confirmation (`linear`).
    const auto through = [&](TermFamily f, bool linear) {
      f.acts_through = x;
      f.linear = linear;
      out.push_back(std::move(f));
    };
    const std::vector<double> widths = log_grid(0.01 * span, 0.4 * span, kTermScanPoints);
    through(scanned("deadzone", x, "w", widths), false);
    through(scanned("backlash", x, "w", widths), false);
    if (span > 0.0) through(scanned("sat", x, "s", log_grid(0.25 * span, 0.95 * span, kTermScanPoints)), false);
    if (rate > 0.0) through(scanned("ratelimit", x, "r", log_grid(0.1 * rate, rate, kTermScanPoints)), true);
    through(scanned("lag", x, "tau", log_grid(kLagGridS[0], kLagGridS[1], kTermScanPoints)), true);
  }
  return out;
}

const VectorXd& Workflow::term_column_of(const TermExpression& expr) const {
  const std::string key = expr.to_string();
  auto it = term_columns.find(key);
  if (it == term_columns.end()) it = term_columns.emplace(key, term_column(data, Term{"L", expr, 0.0, ""})).first;
  return it->second;
}

void Workflow::acts_through(const TermFamily& fam, const Model& m, std::size_t eq, const ScanPoint& P,
                            CandidateTrial& t) const {
  // The input acts (mostly) through the form, as a delayed input acts mostly delayed
  // (actuator_delay): beside the input's own column, the form's coefficient has the sign of the
  // input's total effect and is at least half of it. A form that only corrects the input's
  // linear effect (a long lag with the opposite sign fits a closed-loop record's low-frequency
  // misfit) is not the input's dead zone, backlash or lag.
  const std::string& eqname = m.eqs[eq].name;
  const std::vector<std::string> names = m.names(eq);
  std::string input_param;  // the input's derivative in this equation, e.g. L_df
  for (const auto& d : control_derivative_names(Structure::kLateral3, fam.acts_through)) {
    if (d.rfind(eqname + "_", 0) == 0) input_param = d;
  }
  const auto it = std::find(names.begin(), names.end(), input_param);
  if (it == names.end()) return;
  // The fit on all folds, from the scan point's statistics: the model's columns, then the form's.
  const FoldStats& fs = P.stats[eq];
  VectorXd th;
  if (!solve(fs.Gt, fs.bt, th)) return;
  const double own = th[static_cast<Index>(it - names.begin())], form = th[th.size() - 1];
  const double fraction = own + form != 0.0 ? form / (own + form) : 0.0;
  t.parameters["fraction_through_form"] = fraction;
  if (fraction < 0.5) {
    t.passed = false;
    t.reason = "fails: " + fam.acts_through + " does not act mostly through " + t.expression + " (fraction " +
               fmt(fraction) + " < 0.5 of its effect in " + eqname +
               "): a correction of its linear effect, not its form; " + t.reason.substr(t.reason.find(':') + 1);
  }
}

void Workflow::instrument_confirms(const TermExpression& expr, const Model& m, std::size_t eq, std::size_t family_count,
                                   const TermConfirmation& confirm, CandidateTrial& t) const {
  // A linear term of a slow signal (phi in the side force) has little above the gust band, and
  // its excitation part lies in the excitation's span, which excitation_confirms projects out.
  // Instead the equation is refit with every regressor replaced by its excitation part
  // (instrumented_wald): under the model, and under a side gust, the equation error is
  // independent of the excitation, so the test holds its level where the least-squares test
  // meets the feedback's bias (measured on the open generator's 200 nulls: coefficient / sigma
  // of phi in L, mean -1.22 by least squares, -0.18 instrumented).
  if (!confirm.frame) {
    t.passed = false;
    t.reason = "fails: no exogenous signal to instrument the term by (" + t.reason + ")";
    return;
  }
  MatrixXd C(data.size(), 1);
  C.col(0) = term_column_of(expr);
  const double p = std::min(1.0, instrumented_wald(augmented_design(m.eqs[eq], m.added[eq]), m.eqs[eq].y, C,
                                                   confirm.frame->excitation, batch.min_block, nullptr, nullptr) *
                                     static_cast<double>(family_count));
  t.signature["instrumented_p"] = p;
  if (p > opt.gust_band_alpha) {
    t.passed = false;
    t.reason = "fails: not confirmed with the excitation as instruments (p " + fmt(p) + " > " +
               fmt(opt.gust_band_alpha) + ", every regressor replaced by its excitation part, Bonferroni over " +
               std::to_string(family_count) + " terms); " + t.reason.substr(t.reason.find(':') + 1);
  }
}

void Workflow::excitation_confirms(const TermExpression& expr, const std::string& eqname, std::size_t family_count,
                                   const TermConfirmation& confirm, CandidateTrial& t) const {
  // Seen through the excitation, as the location tests see a state (state_findings): the term of
  // the signals' excitation parts against the residual of the model and the excitation's bank.
  // Under a linear plant that residual is process and measurement noise, independent of any
  // function of the excitation, so the test holds its level in closed loop with noisy
  // regressors, where the term of the measured signals can fit the regression's own bias.
  if (!confirm.frame) {
    t.passed = false;
    t.reason = "fails: no exogenous signal to confirm the term against (" + t.reason + ")";
    return;
  }
  const Term term{eqname, expr, 0.0, ""};
  const VectorXd col = term_column(*confirm.excitation_parts, term);
  double p = 1.0;
  if (col.allFinite() && excited(col, "")) {
    MatrixXd C(col.size(), 1);
    C.col(0) = col;
    p = std::min(1.0, frame_wald(*confirm.frame, C, batch.min_block, nullptr) * static_cast<double>(family_count));
  }
  t.signature["excitation_p"] = p;
  if (p > opt.gust_band_alpha) {
    t.passed = false;
    t.reason = "fails: not confirmed through the excitation (p " + fmt(p) + " > " + fmt(opt.gust_band_alpha) +
               " for the term of the signals' excitation parts against the residual of the model and the excitation, "
               "Bonferroni over " +
               std::to_string(family_count) + " terms); " + t.reason.substr(t.reason.find(':') + 1);
  }
}

CandidateTrial Workflow::term_trial(const TermFamily& fam, std::size_t eq, const Model& m,
                                    const std::vector<FoldStats>& base, const std::vector<VectorXd>& base_cv,
                                    std::size_t round, std::size_t family_count, const TermConfirmation& confirm,
                                    std::vector<Addition>& best_adds) const {
  CandidateTrial t;
  t.name = "term";
  t.round = round;
  t.p_critical = p_critical;
  t.equation = m.eqs[eq].name;
  t.expression = fam.label;
  const std::size_t neq = m.eqs.size();
  const std::vector<double> rss_before = full_rss_each(base);
  std::vector<ScanPoint> points;
  const MatrixXd X = m.X(eq);
  const VectorXd& w = m.eqs[eq].w;
  for (std::size_t i = 0; i < fam.points.size(); ++i) {
    ScanPoint pt;
    pt.k = static_cast<Index>(i);
    const Term term{m.eqs[eq].name, fam.points[i], 0.0, ""};
    VectorXd col = term_column_of(fam.points[i]);
    const bool ok = col.allFinite() && excited(col, "");
    pt.adds = {Addition{eq, {term_parameter_name(term)}, {std::move(col)}}};
    pt.touched.assign(neq, false);
    pt.stats.resize(neq);
    if (ok) {
      // The model's fold statistics bordered by the term's column (as augmented_design weights it).
      const VectorXd& c = pt.adds.front().cols.front();
      pt.stats[eq] = fold_stats_with(base[eq], X, m.eqs[eq].y, w.size() ? VectorXd(c.cwiseProduct(w)) : c, folds);
      pt.touched[eq] = true;
    }
    close_scan_point(pt, rss_before, ok);
    points.push_back(std::move(pt));
  }
  const std::size_t best = best_scan_point(points);
  if (!std::isfinite(points[best].rss_rel)) {
    t.available = false;
    t.reason = "its column is not excited or cannot be separated from the model's";
    return t;
  }
  t.expression = fam.points[best].to_string();
  t.scan_points = points.size();
  CandidateSpec spec;
  spec.name = "term";
  spec.scan = points.size() > 1 ? effects::Scan::kFormParameter : effects::Scan::kNone;
  // The coefficient's variance: the local batch means floored at the stationary residual's
  // (stationary_floor): a product with the throttle lives in the throttle's doublets, a cubic
  // of the rate in the few largest manoeuvres, where batch means rest on a few blocks.
  ScanPoint P = points[best];
  P.stationary_floor = true;
  std::vector<bool> use_eq(neq, false);
  std::string p_eq;
  const double p_min = significance(spec, m, P, rss_before, points.size(), t, use_eq, p_eq);
  // The family-wise rule: Bonferroni over the scan and over every family tried in every equation.
  t.p_value = std::min(1.0, p_min * static_cast<double>(points.size()) * static_cast<double>(family_count));
  use_eq.assign(neq, false);
  use_eq[eq] = t.p_value <= p_critical;
  if (!use_eq[eq]) {
    // Not significant: the trial fails whatever the other rules say, and most families of a
    // round end here, so the others (a high-pass and the cross-validation fits) are not run.
    std::ostringstream why;
    why << "fails: not significant (p " << fmt(t.p_value) << " > " << fmt(p_critical);
    if (!p_eq.empty()) why << ", F " << fmt(t.partial_f[p_eq]) << " in " << p_eq;
    why << "; the other rules not tried)";
    t.reason = why.str();
    return t;
  }
  // The confirmation above the gust band at the family's level too: a slow form (a long lag of
  // the input, a product of slow signals) fits a closed-loop record's low-frequency misfit.
  // The confirmations hold the family-wise rate among the families that reach them: under the
  // null a valid significance rule lets through at most its own level, and where a bias (a side
  // gust's, the regression's own in closed loop) lets families through, the confirmations are
  // Bonferroni'd over those (term_search), not over every family tried.
  const std::size_t confirm_count = confirm.bonferroni > 0 ? confirm.bonferroni : family_count;
  if (!p_eq.empty() && !fam.instrumented)
    t.highpass_p = std::min(1.0, above_gust_band(m, P, points.size()) * static_cast<double>(confirm_count));
  if (!heldout(spec, m, points, best, base, base_cv, use_eq, ChangeProfile{}, t)) {
    t.reason = "a cross-validation fit is singular (the term is not excited in every block)";
    return t;
  }
  judge(t, p_eq);
  if (t.passed && !fam.acts_through.empty()) acts_through(fam, m, eq, P, t);
  if (t.passed && !fam.linear) excitation_confirms(fam.points[best], m.eqs[eq].name, confirm_count, confirm, t);
  if (t.passed && fam.instrumented) instrument_confirms(fam.points[best], m, eq, confirm_count, confirm, t);
  if (t.passed) best_adds = P.adds;
  return t;
}

void Workflow::rival_form_signature(const CandidateSpec& spec, const Model& m, const ScanPoint& P,
                                    CandidateTrial& t) const {
  // A library effect's form must be the data's form. In each equation where the effect's terms
  // met the partial-F rule (the roll moment and the side force; not the actuator's own equation,
  // where a lag is the actuator's pole, which the baseline refits), the generic term that alone
  // fits all the data best (term_families: the open world's, among them a first-order lag of the
  // input, which a pure delay is told from by its gain falling with frequency) is fitted together
  // with the effect's own terms, each tested beside the other (Wald, coloured covariance, at
  // gust_band_alpha; the rival Bonferroni over every generic column tried and the equations).
  // The signature fails where the rival encompasses the effect (below); a delay and a lag that
  // tie in every such equation make the verdict ambiguous.
  const std::vector<std::string>& inputs = opt.inputs.empty() ? model.inputs : opt.inputs;
  const std::vector<TermFamily> families = term_families(data, inputs);
  const double alpha = opt.gust_band_alpha;
  std::size_t compared = 0;
  for (const Addition& own : P.adds) compared += m.eqs[own.eq].name == "L" || m.eqs[own.eq].name == "Y";
  std::string rivals, tied_with;
  bool all_tied = true;
  for (const Addition& own : P.adds) {
    const std::string& eq = m.eqs[own.eq].name;
    if (eq != "L" && eq != "Y") continue;
    // Only where the effect's terms met the partial-F rule: in an equation where the effect is
    // weak, a rival fits what the effect does not claim.
    const auto F = t.partial_f.find(eq);
    if (F == t.partial_f.end() || F->second < opt.partial_f) continue;
    const std::size_t e = own.eq;
    std::vector<Addition> with_own = m.added[e];
    with_own.push_back(own);
    double best_rss = std::numeric_limits<double>::infinity();
    Addition rival;
    std::string rival_text;
    std::size_t tried = 0;
    const Folds whole{{0, m.eqs[e].y.size()}};
    const MatrixXd X = m.X(e);
    const FoldStats model_whole = fold_stats(X, m.eqs[e].y, whole);
    const VectorXd& w = m.eqs[e].w;
    for (const TermFamily& fam : families) {
      for (const TermExpression& expr : fam.points) {
        const Term term{eq, expr, 0.0, ""};
        Addition a{e, {term_parameter_name(term)}, {term_column_of(expr)}};
        if (!a.cols.front().allFinite() || !excited(a.cols.front(), "")) continue;
        ++tried;
        const VectorXd& c = a.cols.front();
        const double r =
            full_rss(fold_stats_with(model_whole, X, m.eqs[e].y, w.size() ? VectorXd(c.cwiseProduct(w)) : c, whole));
        if (std::isfinite(r) && r < best_rss) {
          best_rss = r;
          rival = std::move(a);
          rival_text = expr.to_string();
        }
      }
    }
    if (!std::isfinite(best_rss)) continue;
    std::vector<Addition> all = with_own;
    all.push_back(rival);
    const MatrixXd C = augmented_design(m.eqs[e], all);
    const VectorXd& y = m.eqs[e].y;
    VectorXd theta;
    if (!solve(C.transpose() * C, C.transpose() * y, theta)) continue;
    const VectorXd resid = y - C * theta;
    const Index block = batch.block(resid);
    const MatrixXd cov = coloured_covariance(C, resid, block);
    const double blocks = block_count(C.rows(), block);
    const Index q = C.cols();
    const Index k_own = static_cast<Index>(own.cols.size());
    const double w_rival = theta[q - 1] * theta[q - 1] / cov(q - 1, q - 1);
    const VectorXd th_own = theta.segment(q - 1 - k_own, k_own);
    const double w_own = th_own.dot(cov.block(q - 1 - k_own, q - 1 - k_own, k_own, k_own).ldlt().solve(th_own));
    const double p_rival =
        std::min(1.0, wald_tail(w_rival, 1, blocks) * static_cast<double>(tried) * static_cast<double>(compared));
    const double p_own = wald_tail(w_own, k_own, blocks);
    t.signature["rival_p_" + eq] = p_rival;
    t.signature["own_p_" + eq] = p_own;
    rivals += (rivals.empty() ? "" : ", ") + eq + ": " + rival_text;
    const bool confusable = spec.scan == effects::Scan::kDelay && rival_text.rfind("lag(", 0) == 0;
    // Each alone: the rival's fit against the effect's own, with the same model beside.
    std::vector<Addition> with_rival = m.added[e];
    with_rival.push_back(rival);
    const double rss_own = full_rss(fold_stats(augmented_design(m.eqs[e], with_own), y, whole));
    const double rss_rival = full_rss(fold_stats(augmented_design(m.eqs[e], with_rival), y, whole));
    t.signature["rival_rss_ratio_" + eq] = rss_rival / rss_own;
    // A tie: alone the rival fits better and beside it the effect's terms add nothing, but it is
    // not significant beside them either, so in this equation the record cannot tell the two
    // forms apart. A verdict only between a pure delay and a first-order lag, two physics (a
    // transport delay, the actuator's own dynamics) that a record of slow manoeuvres cannot tell
    // apart; another shape of the same dependence that fits as well (v^3 beside v|v|) is the
    // same effect with another law, reported with the rival's figures but not as ambiguous.
    const bool tie = confusable && rss_rival < rss_own && p_own > alpha && p_rival > alpha;
    all_tied = all_tied && tie;
    if (tie && tied_with.empty()) tied_with = "term " + eq + ": " + rival_text;
    // The rival encompasses the effect: alone it fits better, beside the effect's terms it is
    // significant, and they add nothing beside it. For the delay and a lag (the one pair of
    // physics the rig knows to be confusable), a lag significant beside the delay and better
    // alone is enough: a delay beside a lag only mends the lag's grid.
    const bool encompassed = p_rival <= alpha && rss_rival < rss_own && (confusable || p_own > alpha);
    if (encompassed && t.signature_holds) {
      t.signature_holds = false;
      t.signature_note = "in " + eq + " the generic term " + rival_text + " fits better than " + spec.name +
                         "'s terms (residual sum of squares " + fmt(rss_rival / rss_own) + " of theirs) and is " +
                         "significant beside them (p " + fmt(p_rival) + ", Bonferroni over " + std::to_string(tried) +
                         " terms; theirs beside it p " + fmt(p_own) + "): the data's form is not " + spec.name + "'s";
    }
  }
  t.signature_rival = rivals;
  // Ambiguous when every equation where the effect is significant is a tie.
  if (all_tied && !tied_with.empty() && t.signature_holds) {
    t.ambiguous_with = tied_with;
    t.tell_apart = tell_apart(tied_with.substr(tied_with.find(": ") + 2), spec);
  }
}

void scan_interval(const Workflow& wf, const Model& m, const TermFamily& fam, std::size_t eq, CandidateTrial& t,
                   Addition& add) {
  if (fam.values.size() < 2) return;
  std::size_t best = 0;
  while (best < fam.points.size() && fam.points[best].to_string() != t.expression) ++best;
  if (best == fam.points.size()) return;
  std::vector<double> grid = fam.values;
  const double lo = fam.values[best == 0 ? 0 : best - 1], hi = fam.values[std::min(best + 1, fam.values.size() - 1)];
  const std::size_t fine = 16 * (best == 0 || best + 1 == fam.values.size() ? 1 : 2);
  for (double v : log_grid(lo, hi, fine + 1)) grid.push_back(v);
  std::sort(grid.begin(), grid.end());
  const MatrixXd X = m.X(eq);
  const VectorXd& y = m.eqs[eq].y;
  const VectorXd& w = m.eqs[eq].w;
  const Folds whole{{0, y.size()}};
  const FoldStats model_whole = fold_stats(X, y, whole);
  std::vector<double> rss(grid.size(), std::numeric_limits<double>::infinity());
  std::vector<std::string> texts(grid.size());
  std::size_t arg = 0;
  for (std::size_t i = 0; i < grid.size(); ++i) {
    texts[i] = fam.prefix + number_text(grid[i]) + ")";
    const VectorXd& c = wf.term_column_of(TermExpression::parse(texts[i]));
    if (!c.allFinite()) continue;
    const double r = full_rss(fold_stats_with(model_whole, X, y, w.size() ? VectorXd(c.cwiseProduct(w)) : c, whole));
    if (std::isfinite(r)) rss[i] = r;
    if (rss[i] < rss[arg]) arg = i;
  }
  if (!std::isfinite(rss[arg])) return;
  // The scale of the profile, 1 / (s2 kappa), at the best point: change_profile's.
  const TermExpression at = TermExpression::parse(texts[arg]);
  const VectorXd& c = wf.term_column_of(at);
  ScanPoint P;
  P.adds = {Addition{eq, {term_parameter_name(Term{m.eqs[eq].name, at, 0.0, ""})}, {c}}};
  P.stats.resize(m.eqs.size());
  P.stats[eq] = fold_stats_with(model_whole, X, y, w.size() ? VectorXd(c.cwiseProduct(w)) : c, whole);
  const double scale = wf.change_profile(m, P).scale[eq];
  if (!(scale > 0.0)) return;
  const double crit = 3.841458820694124;  // chi2_1's 95 % point
  std::size_t first = arg, last = arg;
  for (std::size_t i = 0; i < grid.size(); ++i) {
    if ((rss[i] - rss[arg]) * scale > crit) continue;
    first = std::min(first, i);
    last = std::max(last, i);
  }
  // Half a fine step past an accepted point of the fine grid; to the next grid point past one of
  // the coarse grid outside it (the parameter between two coarse points is fitted by either).
  const double half_step = std::pow(hi / lo, 0.5 / static_cast<double>(fine));
  const auto fine_point = [&](std::size_t i) { return grid[i] >= lo * (1.0 - 1e-12) && grid[i] <= hi * (1.0 + 1e-12); };
  t.expression = at.to_string();
  t.parameters[fam.parameter] = grid[arg];
  t.parameters[fam.parameter + "_lo"] =
      first == 0 ? grid.front() : (fine_point(first) ? grid[first] / half_step : grid[first - 1]);
  t.parameters[fam.parameter + "_hi"] =
      last + 1 == grid.size() ? grid.back() : (fine_point(last) ? grid[last] * half_step : grid[last + 1]);
  add = P.adds.front();
}

void test_given_terms(const Workflow& wf, const Model& m, DiscrepancyResult& res) {
  if (wf.opt.test_terms.empty()) return;
  const Excitation ex = excitation_bank(wf.data, wf.opt.excitation);
  const std::optional<Span> instruments = ex.signals.empty() ? std::nullopt : std::optional<Span>(Span(ex.Z));
  for (const Term& given : wf.opt.test_terms) {
    TermTest out;
    out.equation = given.equation;
    out.expression = given.expression.to_string();
    std::size_t e = m.eqs.size();
    for (std::size_t i = 0; i < m.eqs.size(); ++i) {
      if (m.eqs[i].name == given.equation) e = i;
    }
    if (e == m.eqs.size()) {
      std::string have;
      for (const auto& eq : m.eqs) have += (have.empty() ? "" : ", ") + eq.name;
      throw std::invalid_argument("discrepancy: the form to test " + given.equation + ": " + out.expression +
                                  " names equation " + given.equation + ", which this record has not (" + have + ")");
    }
    const Term term{given.equation, given.expression, 0.0, ""};
    Addition a{e, {term_parameter_name(term)}, {term_column(wf.data, term)}};
    const VectorXd& col = a.cols.front();
    AdditionFit f;
    if (!col.allFinite() || !excited(col, "")) {
      out.note = "its column is not finite or not excited on this record";
    } else {
      std::vector<Addition> all = m.added[e];
      all.push_back(a);
      const MatrixXd C = augmented_design(m.eqs[e], all);
      const Folds whole{{0, C.rows()}};
      const FoldStats with = fold_stats(C, m.eqs[e].y, whole);
      const double rss_before = full_rss(fold_stats(m.X(e), m.eqs[e].y, whole));
      if (!fit_addition(m, a, with, rss_before, wf.batch, f)) {
        out.note = "its column cannot be separated from the model's";
      } else {
        stationary_floor(m, a, wf.batch, f);  // the search's own variance for a term
        out.coefficient = f.theta[f.off];
        out.sigma = std::sqrt(std::max(0.0, f.cov(f.off, f.off)));
        out.wald = f.wald;
        out.p_value = f.p;
        out.blocks = f.blocks;
        if (instruments) {
          MatrixXd c(col.size(), 1);
          c.col(0) = col;
          out.iv_p_value = instrumented_wald(augmented_design(m.eqs[e], m.added[e]), m.eqs[e].y, c, *instruments,
                                             wf.batch.min_block, &out.iv_coefficient, &out.iv_sigma);
        }
      }
    }
    res.term_tests.push_back(std::move(out));
  }
}

void term_search(const Workflow& wf, const std::vector<std::string>& inputs, Model& m, DiscrepancyResult& res) {
  const std::vector<TermFamily> families = term_families(wf.data, inputs);
  std::vector<std::size_t> eqs;  // the roll moment and the side force (not the actuator's own equation)
  for (std::size_t e = 0; e < m.eqs.size(); ++e) {
    if (m.eqs[e].name == "L" || m.eqs[e].name == "Y") eqs.push_back(e);
  }
  const std::size_t family_count = families.size() * eqs.size();
  // The excitation (the location tests' bank) and each signal's excitation part.
  const Excitation ex = excitation_bank(wf.data, wf.opt.excitation);
  UniformData excitation_parts;
  if (!ex.signals.empty()) {
    excitation_parts = wf.data;
    const Span span(ex.Z);
    for (auto& [name, x] : excitation_parts.signals) {
      if (x.size() == ex.Z.rows()) x = span.project(x);
    }
  }
  std::vector<std::size_t> done;  // the equations a term entered
  for (std::size_t round = 1; round <= wf.opt.term_rounds; ++round) {
    const std::vector<FoldStats> base = model_stats(m, wf.folds);
    const std::vector<VectorXd> base_cv = heldout_residuals(m, wf.folds);
    std::map<std::size_t, TermConfirmation> confirm;  // without an exogenous signal: no frame
    for (std::size_t e : eqs) {
      TermConfirmation& c = confirm[e];
      if (ex.signals.empty()) continue;
      c.frame = std::make_unique<LocationFrame>(m.X(e), m.eqs[e].y, ex.Z);
      c.excitation_parts = &excitation_parts;
    }
    struct Pass {
      CandidateTrial trial;
      std::vector<Addition> adds;
      const TermFamily* family = nullptr;
    };
    std::vector<Pass> passing;
    CandidateTrial closest;  // the smallest p of the round, reported when nothing passes
    closest.p_value = 2.0;
    // First every family against the significance rule (a family that fails it ends there), then
    // the confirmations of those that met it, Bonferroni'd over their number.
    std::vector<std::pair<std::size_t, const TermFamily*>> significant;
    for (std::size_t e : eqs) {
      // One form per equation: a later round looks for the effect in the other equation.
      if (std::find(done.begin(), done.end(), e) != done.end()) continue;
      for (const TermFamily& fam : families) {
        std::vector<Addition> adds;
        CandidateTrial t = wf.term_trial(fam, e, m, base, base_cv, round, family_count, confirm.at(e), adds);
        if (!t.available) continue;
        if (t.p_value <= wf.p_critical) {
          significant.emplace_back(e, &fam);
        } else if (t.p_value < closest.p_value) {
          closest = std::move(t);
        }
      }
    }
    for (auto& [e, c] : confirm) c.bonferroni = significant.size();
    for (const auto& [e, fam] : significant) {
      std::vector<Addition> adds;
      CandidateTrial t = wf.term_trial(*fam, e, m, base, base_cv, round, family_count, confirm.at(e), adds);
      if (t.passed) {
        passing.push_back({std::move(t), std::move(adds), fam});
      } else if (t.p_value < closest.p_value) {
        closest = std::move(t);
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
    if (win.family) scan_interval(wf, m, *win.family, wa.eq, win.trial, win.adds.front());
    done.push_back(wa.eq);
    Term term{m.eqs[wa.eq].name, TermExpression::parse(win.trial.expression), 0.0, "rig discrepancy"};
    m.effect_names.push_back(kTermPrefix + term_parameter_name(term));
    m.found_terms.push_back(std::move(term));
    m.added[wa.eq].push_back(wa);
    for (auto& p : passing) res.candidates.push_back(std::move(p.trial));
  }
}

}  // namespace nimble::ident::discrepancy_parts
