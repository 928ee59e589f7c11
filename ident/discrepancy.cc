// The discrepancy workflow (ident/discrepancy.h): the candidate library and find_discrepancy(),
// which joins the parts of ident/discrepancy_parts.h.

#include "ident/discrepancy.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>
#include <stdexcept>


#include "core/chi_square.h"
#include "ident/metrics.h"
#include "ident/spectrum.h"
#include "ident/discrepancy_parts.h"

namespace nimble::ident {

using namespace discrepancy_parts;

const std::vector<CandidateSpec>& candidate_library() { return effect_registry(); }

namespace {

/// Refuses a model or options the workflow cannot run on.
void check_request(const DerivativeModel& model, const DiscrepancyOptions& options) {
  if (model.structure != Structure::kLateral3) {
    throw std::invalid_argument("rig discrepancy works on lateral3 models; '" + model.name + "' is " +
                                to_string(model.structure));
  }
  if (options.folds < 4) throw std::invalid_argument("discrepancy: folds must be >= 4");
  if (!(options.partial_f > 0.0)) throw std::invalid_argument("discrepancy: partial F must be > 0");
  if (!(options.delay_max_s > 0.0)) throw std::invalid_argument("discrepancy: delay_max_s must be > 0");
  for (const auto& name : options.candidates) {
    if (find_effect(name) == nullptr) {
      throw std::invalid_argument("unknown candidate '" + name + "' (known: " + effect_name_list() + ")");
    }
  }
}

/// The stepwise search: in each round every candidate not yet in the model is tried; the
/// passing one with the largest held-out drop enters, and another passing one that explains
/// the same thing makes the result ambiguous.
void stepwise_search(const Workflow& wf, const std::vector<const CandidateSpec*>& pool,
                     const std::vector<std::string>& known, Model& m, DiscrepancyResult& res) {
  // Stepwise search.
  std::vector<std::string> entered = known;
  for (std::size_t round = 1; round <= wf.opt.max_effects; ++round) {
    const std::vector<FoldStats> base = model_stats(m, wf.folds);
    const std::vector<VectorXd> base_cv = heldout_residuals(m, wf.folds);
    struct Pass {
      std::size_t trial;
      std::vector<Addition> adds;
    };
    std::vector<Pass> passing;
    for (const CandidateSpec* spec : pool) {
      if (spec->wideband || spec->stochastic) continue;  // the wideband and signature stages below
      if (std::find(entered.begin(), entered.end(), spec->name) != entered.end()) continue;
      std::vector<Addition> adds;
      res.candidates.push_back(wf.trial(*spec, m, base, base_cv, round, adds));
      if (res.candidates.back().passed) passing.push_back({res.candidates.size() - 1, std::move(adds)});
    }
    if (passing.empty()) break;
    std::size_t best = 0;
    for (std::size_t i = 1; i < passing.size(); ++i) {
      if (res.candidates[passing[i].trial].heldout_drop > res.candidates[passing[best].trial].heldout_drop) best = i;
    }
    // Another passing candidate that explains the same thing: ambiguous.
    for (std::size_t i = 0; i < passing.size(); ++i) {
      if (i == best) continue;
      double rho_max = 0.0;
      for (const auto& a : passing[best].adds) {
        for (const auto& b : passing[i].adds) {
          if (a.eq != b.eq) continue;
          const MatrixXd X = m.X(a.eq);
          for (const auto& ca : a.cols) {
            for (const auto& cb : b.cols) rho_max = std::max(rho_max, std::fabs(residual_correlation(X, ca, cb)));
          }
        }
      }
      if (rho_max > wf.opt.collinearity) {
        res.ambiguous.push_back({res.candidates[passing[best].trial].name, res.candidates[passing[i].trial].name});
        res.candidates[passing[i].trial].reason +=
            "; explains the same as " + res.candidates[passing[best].trial].name + " (|rho| " + fmt(rho_max) + ")";
      }
    }
    CandidateTrial& win = res.candidates[passing[best].trial];
    win.entered = true;
    win.reason = "entered: " + win.reason;
    entered.push_back(win.name);
    for (auto& a : passing[best].adds) m.added[a.eq].push_back(std::move(a));
    m.effect_names.push_back(win.name);
    // Candidates that passed with this one but explain the same thing are not tried again.
    for (const auto& pair : res.ambiguous) {
      if (pair[0] == win.name) entered.push_back(pair[1]);
    }
  }
}

/// The wideband stage (flapping forcing above the identification low-pass).
void wideband_stage(const FlightData& data, const DerivativeModel& model, const Vehicle& vehicle,
                    const DiscrepancyOptions& options, const std::vector<Equation>& equations,
                    const std::vector<const CandidateSpec*>& pool, const std::vector<std::string>& known,
                    const Workflow& wf, Model& m, DiscrepancyResult& res) {
  // Wideband stage: flapping forcing lies above the identification low-pass. The model as
  // it now stands (baseline, known and named effects) is refit on the same data low-passed at
  // flapping_cutoff_hz, and harmonics at a frequency scanned over the flapping band are tried
  // with the same entry rule (Bonferroni over the independent frequencies of the band).
  const auto flapping = std::find_if(pool.begin(), pool.end(), [](const CandidateSpec* c) { return c->wideband; });
  if (flapping != pool.end() && std::find(known.begin(), known.end(), (*flapping)->name) == known.end()) {
    ProcessingOptions wide_proc = options.processing;
    wide_proc.filter_order = 10;
    wide_proc.cutoff_hz = std::min(options.flapping_cutoff_hz, 0.4 * options.processing.rate_hz);
    PreparedData wide = prepare(data, Structure::kLateral3, model.trim, vehicle.gravity_mps2, wide_proc);
    add_applied_command(wide.filtered, options.command_latency_s);
    Model wm = build_baseline(wide.filtered, equations, model, vehicle, data.source, nullptr, nullptr);
    for (const auto& name : m.effect_names) {
      const CandidateSpec& spec = *find_effect(name);
      Index k = 0;
      for (const auto& t : res.candidates) {
        if (t.name == name && t.entered) k = scan_index(name, t.parameters, wide.filtered);
      }
      for (auto& a : candidate_columns(spec, wide.filtered, model.trim, vehicle.gravity_mps2, k)) wm.added[a.eq].push_back(a);
    }
    BatchRule wide_batch = wf.batch;
    wide_batch.min_block = static_cast<Index>(4 * whiteness_lag_step(0, wide_proc));
    CandidateTrial t = flapping_trial(wm, wide.filtered, wf.folds, options, wf.p_critical, wide_batch);
    if (t.passed) {
      t.entered = true;
      t.reason = "entered: " + t.reason;
      NamedEffect eff;
      eff.name = t.name;
      eff.parameters = t.parameters;
      eff.sigma = t.sigma;
      res.effects.push_back(eff);
      m.effect_names.push_back(t.name);
    }
    res.candidates.push_back(std::move(t));
  }
}

/// The lateral gust, named from its signature in the final residual (it has no regressor).
CandidateTrial gust_stage(const UniformData& d, const DerivativeModel& model, const Vehicle& vehicle,
                          const DiscrepancyOptions& options, const std::vector<const CandidateSpec*>& pool,
                          const std::vector<std::string>& known, const std::map<std::string, double>& known_values,
                          const Workflow& wf, const Model& m, const std::vector<VectorXd>& aug_resid,
                          DiscrepancyResult& res) {
  // A side wind has no regressor: named from its signature in the final residual.
  const auto gust = std::find_if(pool.begin(), pool.end(), [](const CandidateSpec* c) { return c->stochastic; });
  CandidateTrial gust_result;
  const double f_ref_hi =
      options.processing.filter_order > 0 ? 0.6 * options.processing.cutoff_hz : 0.45 * d.rate_hz;
  if (gust != pool.end() && std::find(known.begin(), known.end(), (*gust)->name) == known.end()) {
    std::vector<VectorXd> extra;  // Y columns of every deterministic candidate the data supports
    for (const auto& c : candidate_library()) {
      if (c.scanned || c.wideband || c.stochastic) continue;
      if (std::find(m.effect_names.begin(), m.effect_names.end(), c.name) != m.effect_names.end()) continue;
      if (std::find(known.begin(), known.end(), c.name) != known.end()) continue;
      if (!std::all_of(c.needs.begin(), c.needs.end(), [&](const std::string& n) { return d.has(n) && excited(d.at(n), n); })) {
        continue;
      }
      for (auto& a : candidate_columns(c, d, model.trim, vehicle.gravity_mps2, 0)) {
        if (m.eqs[a.eq].name != "Y") continue;
        for (auto& col : a.cols) extra.push_back(std::move(col));
      }
    }
    VectorXd given_resid;
    double yv_given = 0.0;
    for (std::size_t e = 0; e < m.eqs.size(); ++e) {
      if (m.eqs[e].name != "Y" || !model.derivatives.count("Yv")) continue;
      given_resid = m.eqs[e].y - given_prediction(m.eqs[e], model, known_values, options);
      yv_given = model.derivatives.at("Yv");
    }
    gust_result = gust_trial(m, aug_resid, res.augmented, d.rate_hz, f_ref_hi, extra, given_resid, yv_given, options,
                             wf.p_critical);
    res.candidates.push_back(gust_result);
  }
  return gust_result;
}

/// The named effects with their parameters from the augmented fit (flapping forcing is named by
/// the wideband stage).
void name_effects(const Model& m, const Workflow& wf, DiscrepancyResult& res) {
  for (const auto& name : m.effect_names) {
    if (name == "flapping_forcing") continue;  // named with its parameters by the wideband stage
    NamedEffect eff;
    eff.name = name;
    const CandidateSpec& spec = *find_effect(name);
    for (const auto& term : spec.terms) {
      const auto it = res.augmented.find(term.parameter);
      if (it == res.augmented.end()) continue;
      eff.parameters[term.parameter] = it->second.value;
      eff.sigma[term.parameter] = it->second.sigma_coloured;
    }
    for (const auto& t : res.candidates) {
      if (t.name != name || !t.entered) continue;
      if (name == "actuator_delay") eff.parameters["delay_s"] = t.delay_s;
      time_varying_parameters(m, wf.batch, wf.data, t, eff);  // rate or change time, for effects that change
    }
    res.effects.push_back(std::move(eff));
  }
}

/// Where the baseline structure's residual lives (frequency, time, nonlinear state dependence).
void locate(const UniformData& d, const DiscrepancyOptions& options, const Model& m,
            const std::vector<VectorXd>& base_resid, const BatchRule& batch, DiscrepancyResult& res) {
  // Location, on the baseline structure's residual.
  const Segments seg = find_segments(d, options.segments);
  const double f_hi = options.processing.filter_order > 0 ? 0.8 * options.processing.cutoff_hz : 0.45 * d.rate_hz;
  for (std::size_t e = 0; e < m.eqs.size(); ++e) {
    const VectorXd r = base_resid[e] / m.eqs[e].scale;
    time_findings(m.eqs[e].output, r, d, seg, options.window_s, res.located.time);
    frequency_peaks(m.eqs[e].output, r, d.rate_hz, 0.5, f_hi, options.location_alpha / 2.0, res.located.frequency);
  }
  {
    Model base_model = m;
    for (auto& a : base_model.added) a.clear();
    for (std::size_t e = 0; e < m.eqs.size(); ++e) {
      state_findings(base_model, e, d, batch, options.location_alpha / 2.0, res.located.state);
    }
  }
}

/// The gap table: each equation's held-out error before and after, and the mean gap.
void gap_table(const UniformData& d, const DerivativeModel& model, const DiscrepancyOptions& options,
               const std::map<std::string, double>& known_values, const Model& m,
               const std::vector<VectorXd>& cv_before, const std::vector<VectorXd>& cv_after, DiscrepancyResult& res) {
  // Gap table.
  const Index n = d.size();
  const std::size_t lag_step = whiteness_lag_step(0, options.processing);
  double gb = 0.0, ga = 0.0;
  for (std::size_t e = 0; e < m.eqs.size(); ++e) {
    const Eq& eq = m.eqs[e];
    OutputGap g;
    g.output = eq.output;
    g.unit = eq.unit;
    const VectorXd model_fit = given_prediction(eq, model, known_values, options);
    const VectorXd y = eq.y / eq.scale;
    const double sst = (y.array() - y.mean()).square().sum();
    const VectorXd rb = cv_before[e] / eq.scale, ra = cv_after[e] / eq.scale;
    g.rmse_model = std::sqrt((eq.y - model_fit).squaredNorm() / static_cast<double>(n)) / eq.scale;
    g.rmse_before = std::sqrt(rb.squaredNorm() / static_cast<double>(n));
    g.rmse_after = std::sqrt(ra.squaredNorm() / static_cast<double>(n));
    g.fit_before_pct = 100.0 * (1.0 - rb.norm() / std::sqrt(sst));
    g.fit_after_pct = 100.0 * (1.0 - ra.norm() / std::sqrt(sst));
    g.white_before = residual_whiteness(rb, d.rate_hz, options.whiteness_lags, lag_step).white;
    g.white_after = residual_whiteness(ra, d.rate_hz, options.whiteness_lags, lag_step).white;
    for (const auto& f : res.located.frequency) {
      if (f.output != eq.output) continue;
      const Psd pb = periodogram(rb, d.rate_hz), pa = periodogram(ra, d.rate_hz);
      const Index k = static_cast<Index>(std::lround(f.f_hz / pb.df_hz));
      g.peak_psd_before = pb.psd[k];
      g.peak_psd_after = pa.psd[k];
    }
    g.measured = y;
    g.predicted_before = y - rb;
    g.predicted_after = y - ra;
    gb += rb.squaredNorm() / sst;
    ga += ra.squaredNorm() / sst;
    res.gap.push_back(g);
  }
  res.gap_before = gb / static_cast<double>(m.eqs.size());
  res.gap_after = ga / static_cast<double>(m.eqs.size());
  res.gap_metric =
      "mean over the equations (L, Y, and F when the data has the actuator command) of the held-out squared equation error divided by the sum of squares of the "
      "dependent about its mean (1 - R^2 on data the fit did not see, " + std::to_string(options.folds) +
      "-fold cross-validation over contiguous blocks)";
}

/// The verdict and its one-line summary.
void judge(const CandidateTrial& gust_result, DiscrepancyResult& res) {
  // Verdict.
  const bool structure_found = !res.located.frequency.empty() || !res.located.state.empty();
  if (!res.ambiguous.empty()) {
    res.verdict = "ambiguous";
  } else if (!res.effects.empty()) {
    res.verdict = "effects";
  } else if (structure_found) {
    res.verdict = "unexplained";
  } else {
    res.verdict = "none";
  }
  std::ostringstream s;
  if (res.verdict == "effects" || res.verdict == "ambiguous") {
    s << "named:";
    for (const auto& e : res.effects) s << " " << e.name;
    for (const auto& pair : res.ambiguous) s << "; " << pair[0] << " and " << pair[1] << " explain the same thing";
    s << "; held-out gap " << fmt(res.gap_before) << " -> " << fmt(res.gap_after);
    if (gust_result.entered) {
      s << " (lateral_gust is random: it has no regressor and leaves the gap as it is; its evidence is the "
           "residual spectrum)";
    }
  } else if (res.verdict == "unexplained") {
    s << "no candidate passes, but the residual has structure:";
    for (const auto& f : res.located.frequency) s << " " << f.output << " peak at " << fmt(f.f_hz) << " Hz;";
    for (const auto& f : res.located.state) s << " " << f.output << " depends nonlinearly on " << f.signal << ";";
  } else {
    s << "nothing significant: no candidate passes and the residual shows no structure";
  }
  res.summary = s.str();
}

/// The model refit with the named effects (its effects: section), as --model-out writes it.
DerivativeModel augmented_model(const FlightData& data, const DerivativeModel& model,
                                const std::vector<std::string>& inputs, const std::vector<std::string>& known,
                                const DiscrepancyResult& res) {
  // The augmented model.
  DerivativeModel am = model;
  am.name = model.name + "_augmented";
  am.source = "rig discrepancy " + data.source + " on " + model.name;
  am.inputs = inputs;
  am.derivatives.clear();
  am.published_sigma.clear();
  am.published_eigenvalues.clear();
  std::vector<std::string> names = stability_derivative_names(Structure::kLateral3);
  for (const auto& in : inputs) {
    for (const auto& nm : control_derivative_names(Structure::kLateral3, in)) names.push_back(nm);
  }
  for (const auto& nm : names) {
    am.derivatives[nm] = res.augmented.at(nm).value;
    am.published_sigma[nm] = res.augmented.at(nm).sigma_coloured;
  }
  am.effects.clear();
  for (const auto& name : known) {
    const auto& spec = *find_effect(name);
    for (const auto& term : spec.terms) {
      const auto it = res.augmented.find(term.parameter);
      if (it != res.augmented.end()) am.effects[name][term.parameter] = it->second.value;
    }
    const auto& given = model.effects.at(name);
    for (const char* scanned : {"delay_s", "t_change_s"}) {
      if (given.count(scanned)) am.effects[name][scanned] = given.at(scanned);
    }
    if (spec.stochastic) am.effects[name] = given;
  }
  for (const auto& e : res.effects) am.effects[e.name] = e.parameters;
  return am;
}

}  // namespace

DiscrepancyResult find_discrepancy(const FlightData& data, const DerivativeModel& model, const Vehicle& vehicle,
                                   const DiscrepancyOptions& options) {
  check_request(model, options);

  DiscrepancyResult res;
  res.source = data.source;
  res.model_name = model.name;
  const std::vector<std::string> inputs = options.inputs.empty() ? model.inputs : options.inputs;
  for (const auto& in : inputs) {
    if (!data.has(in)) throw DataError(data.source, -1, -1, in, "the model's input " + in + " is not in the data");
  }
  PreparedData prep = prepare(data, Structure::kLateral3, model.trim, vehicle.gravity_mps2, options.processing);
  add_applied_command(prep.filtered, options.command_latency_s);
  const UniformData& d = prep.filtered;
  const Index n = d.size();
  if (n < static_cast<Index>(50 * options.folds)) {
    throw DataError(data.source, -1, -1, "", std::to_string(n) + " samples are too few for " +
                                                 std::to_string(options.folds) + "-fold cross-validation");
  }
  res.rate_hz = d.rate_hz;
  res.cutoff_hz = options.processing.filter_order > 0 ? options.processing.cutoff_hz : 0.0;
  res.t_s = d.t_s;
  res.samples = static_cast<std::size_t>(n);
  res.folds = options.folds;

  // Baseline equations (the model's structure with the effects the model file carries).
  const auto equations = lateral_equations(Structure::kLateral3, inputs, vehicle);
  std::vector<std::string> known;
  std::map<std::string, double> known_values;
  Model m = build_baseline(d, equations, model, vehicle, data.source, &known, &known_values);

  Workflow wf{options, vehicle, model, d, make_folds(n, options.folds), {}, 0.0, {}};
  wf.batch.min_block = static_cast<Index>(4 * whiteness_lag_step(0, options.processing));
  wf.p_critical = chi_square_survival(options.partial_f, 1.0);

  std::vector<const CandidateSpec*> pool;
  for (const auto& c : candidate_library()) {
    if (options.candidates.empty() ||
        std::find(options.candidates.begin(), options.candidates.end(), c.name) != options.candidates.end()) {
      pool.push_back(&c);
    }
  }

  // Baseline fit and its held-out residuals.
  std::vector<VectorXd> base_resid;
  res.baseline = full_fit(m, wf.batch, &base_resid);
  const std::vector<VectorXd> cv_before = heldout_residuals(m, wf.folds);

  stepwise_search(wf, pool, known, m, res);
  wideband_stage(data, model, vehicle, options, equations, pool, known, wf, m, res);

  // The augmented fit and the gap after.
  std::vector<VectorXd> aug_resid;
  res.augmented = full_fit(m, wf.batch, &aug_resid);
  const std::vector<VectorXd> cv_after = heldout_residuals(m, wf.folds);
  const CandidateTrial gust_result = gust_stage(d, model, vehicle, options, pool, known, known_values, wf, m, aug_resid, res);
  name_effects(m, wf, res);
  if (gust_result.entered) res.effects.push_back({gust_result.name, gust_result.parameters, gust_result.sigma});
  locate(d, options, m, base_resid, wf.batch, res);
  gap_table(d, model, options, known_values, m, cv_before, cv_after, res);
  judge(gust_result, res);
  res.augmented_model = augmented_model(data, model, inputs, known, res);
  return res;
}

}  // namespace nimble::ident
