// The discrepancy workflow (discrepancy/discrepancy.h): the candidate library and find_discrepancy(),
// which joins the parts of discrepancy/discrepancy_parts.h.

#include "discrepancy/discrepancy.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "core/chi_square.h"
#include "ident/data_check.h"
#include "ident/metrics.h"
#include "ident/spectrum.h"
#include "discrepancy/discrepancy_location.h"
#include "discrepancy/discrepancy_compat_parts.h"
#include "discrepancy/discrepancy_parts.h"
#include "discrepancy/discrepancy_pool_parts.h"

namespace nimble::ident {

using namespace discrepancy_parts;

const std::vector<CandidateSpec>& candidate_library() {
  static const std::vector<CandidateSpec> library = [] {
    std::vector<CandidateSpec> out;
    for (const auto& e : effects::effect_registry()) out.push_back(e.definition);
    return out;
  }();
  return library;
}

namespace {

/// What the search starts from: the candidates it may try and the effects the model file
/// carries (refit with the derivatives, not tried again), with their values as the file gives them.
struct SearchScope {
  std::vector<const CandidateSpec*> pool;
  std::vector<std::string> known;
  std::map<std::string, double> known_values;
};

/// Refuses a model or options the workflow cannot run on.
void check_request(const DerivativeModel& model, const DiscrepancyOptions& options) {
  if (model.structure != Structure::kLateral3) {
    throw std::invalid_argument("rig discrepancy works on lateral3 models; '" + model.name + "' is " +
                                to_string(model.structure));
  }
  effects::check_model_effects(model);  // every effect of its effects: section one the registry knows
  // The command line's ranges (rig discrepancy --help), checked here for every front end (Python).
  const auto value = [](double v) {
    return std::isfinite(v) ? std::to_string(v) : std::string(std::isnan(v) ? "nan" : "inf");
  };
  if (options.folds < 4 || options.folds > 100) {
    throw std::invalid_argument("discrepancy: folds must be in [4, 100], not " + std::to_string(options.folds));
  }
  if (!std::isfinite(options.partial_f) || !(options.partial_f > 0.0)) {
    throw std::invalid_argument("discrepancy: partial_f must be finite and > 0, not " + value(options.partial_f));
  }
  if (!std::isfinite(options.delay_max_s) || !(options.delay_max_s >= 1e-9 && options.delay_max_s <= 1.0)) {
    throw std::invalid_argument("discrepancy: delay_max_s must be in (0, 1] s, not " + value(options.delay_max_s));
  }
  if (!std::isfinite(options.command_latency_s) ||
      !(options.command_latency_s >= 0.0 && options.command_latency_s <= 0.1)) {
    throw std::invalid_argument("discrepancy: command_latency_s must be in [0, 0.1] s, not " +
                                value(options.command_latency_s));
  }
  for (const auto& name : options.candidates) {
    if (effects::find_definition(name) == nullptr) {
      throw std::invalid_argument("unknown candidate '" + name + "' (known: " + effects::effect_name_list() + ")");
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
      if (spec->wideband() || spec->stochastic()) continue;  // the wideband and signature stages below
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
            for (const auto& cb : b.cols) {
              const VectorXd& w = m.eqs[a.eq].w;
              rho_max =
                  std::max(rho_max, std::fabs(w.size() ? residual_correlation(X, ca.cwiseProduct(w), cb.cwiseProduct(w))
                                                       : residual_correlation(X, ca, cb)));
            }
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
    if (!win.ambiguous_with.empty()) {
      // Its signature held, but a generic form fits this record as well (rival_form_signature).
      res.ambiguous.push_back({win.name, win.ambiguous_with});
      win.reason += "; explains the same as the generic " + win.ambiguous_with + " (" + win.tell_apart + ")";
    }
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
void wideband_stage(const Workflow& wf, const SearchScope& scope, const FlightData& data,
                    const std::vector<Equation>& equations, Model& m, DiscrepancyResult& res,
                    std::vector<BandGap>& bands) {
  const DiscrepancyOptions& options = wf.opt;
  const DerivativeModel& model = wf.model;
  const Vehicle& vehicle = wf.vehicle;
  const auto& pool = scope.pool;
  const auto& known = scope.known;
  // Wideband stage: flapping forcing lies above the identification low-pass. The model as
  // it now stands (baseline, known and named effects) is refit on the same data low-passed at
  // flapping_cutoff_hz, and harmonics at a frequency scanned over the flapping band are tried
  // with the same entry rule (Bonferroni over the independent frequencies of the band).
  const auto flapping = std::find_if(pool.begin(), pool.end(), [](const CandidateSpec* c) { return c->wideband(); });
  if (flapping != pool.end() && std::find(known.begin(), known.end(), (*flapping)->name) == known.end()) {
    const CandidateSpec& wide_spec = **flapping;
    ProcessingOptions wide_proc = options.processing;
    wide_proc.filter_order = 10;
    wide_proc.cutoff_hz = std::min(options.flapping_cutoff_hz, 0.4 * options.processing.rate_hz);
    PreparedData wide = prepare(data, Structure::kLateral3, model.trim, vehicle.gravity_mps2, wide_proc);
    add_applied_command(wide.filtered, options.command_latency_s);
    Model wm = build_baseline(wide.filtered, equations, model, vehicle, data.source, nullptr, nullptr);
    for (const Term& term : m.found_terms) {
      for (std::size_t e = 0; e < wm.eqs.size(); ++e) {
        if (wm.eqs[e].name == term.equation)
          wm.added[e].push_back({e, {term_parameter_name(term)}, {term_column(wide.filtered, term)}});
      }
    }
    for (const auto& name : m.effect_names) {
      if (is_found_term(name)) continue;
      const CandidateSpec& spec = *effects::find_definition(name);
      Index k = 0;
      for (const auto& t : res.candidates) {
        if (t.name == name && t.entered) k = scan_index(spec, t.parameters, wide.filtered);
      }
      for (auto& a : candidate_columns(spec, wide.filtered, model.trim, vehicle.gravity_mps2, k))
        wm.added[a.eq].push_back(a);
    }
    BatchRule wide_batch = wf.batch;
    wide_batch.min_block = static_cast<Index>(4 * whiteness_lag_step(0, wide_proc));
    std::vector<VectorXd> cv_before, cv_after;
    CandidateTrial t = flapping_trial(wide_spec, wm, wide.filtered, wf.folds, options, wf.p_critical, wide_batch,
                                      &cv_before, &cv_after);
    if (t.passed) {
      // The gap where the forcing lives: a band at each harmonic, of the record's resolution or
      // kFlappingBandHz wide, in the equations the harmonics enter (not the actuator's).
      const double rate = wide.filtered.rate_hz, T = static_cast<double>(wide.filtered.size()) / rate;
      const double half = std::max(kFlappingBandHz, 1.5 / T);
      std::vector<std::size_t> eqs;
      for (std::size_t e = 0; e < wm.eqs.size(); ++e) {
        if (e != kActuatorEq) eqs.push_back(e);
      }
      std::vector<VectorXd> contribution;
      for (std::size_t e = 0; e < wm.eqs.size(); ++e) contribution.push_back(cv_before[e] - cv_after[e]);
      const double f = t.parameters.at("flapping_hz");
      for (int h = 1; h <= 2; ++h) {
        BandGap g = band_gap(t.name + " harmonic " + std::to_string(h), wm, eqs, cv_before, cv_after, rate,
                             h * f - half, h * f + half, &contribution);
        g.wideband = true;
        bands.push_back(std::move(g));
      }
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
CandidateTrial gust_stage(const Workflow& wf, const SearchScope& scope, const Model& m,
                          const std::vector<VectorXd>& aug_resid, DiscrepancyResult& res) {
  const UniformData& d = wf.data;
  const DiscrepancyOptions& options = wf.opt;
  const DerivativeModel& model = wf.model;
  const Vehicle& vehicle = wf.vehicle;
  const auto& pool = scope.pool;
  const auto& known = scope.known;
  const auto& known_values = scope.known_values;
  // A side wind has no regressor: named from its signature in the final residual.
  const auto gust = std::find_if(pool.begin(), pool.end(), [](const CandidateSpec* c) { return c->stochastic(); });
  CandidateTrial gust_result;
  const double f_ref_hi = options.processing.filter_order > 0 ? 0.6 * options.processing.cutoff_hz : 0.45 * d.rate_hz;
  if (gust != pool.end() && std::find(known.begin(), known.end(), (*gust)->name) == known.end()) {
    GustEvidence evidence{aug_resid, res.augmented, d.rate_hz, f_ref_hi, {}, {}, 0.0};
    std::vector<VectorXd>& extra = evidence.extra;  // Y columns of every deterministic candidate the data supports
    for (const auto& c : candidate_library()) {
      if (c.scanned() || c.wideband() || c.stochastic()) continue;
      if (std::find(m.effect_names.begin(), m.effect_names.end(), c.name) != m.effect_names.end()) continue;
      if (std::find(known.begin(), known.end(), c.name) != known.end()) continue;
      if (!std::all_of(c.needs.begin(), c.needs.end(),
                       [&](const std::string& n) { return d.has(n) && excited(d.at(n), n); })) {
        continue;
      }
      for (auto& a : candidate_columns(c, d, model.trim, vehicle.gravity_mps2, 0)) {
        if (m.eqs[a.eq].name != "Y") continue;
        for (auto& col : a.cols) extra.push_back(std::move(col));
      }
    }
    for (std::size_t e = 0; e < m.eqs.size(); ++e) {
      if (m.eqs[e].name != "Y" || !model.derivatives.count("Yv")) continue;
      evidence.given_resid = m.eqs[e].y - given_prediction(m.eqs[e], model, known_values, options);
      evidence.yv_given = model.derivatives.at("Yv");
    }
    gust_result = gust_trial(**gust, m, evidence, options, wf.p_critical);
    res.candidates.push_back(gust_result);
  }
  return gust_result;
}

/// The named effects with their parameters from the augmented fit (flapping forcing is named by
/// the wideband stage).
void name_effects(const Model& m, const Workflow& wf, DiscrepancyResult& res) {
  for (const Term& term : m.found_terms) {
    NamedEffect eff;
    eff.name = "term";
    eff.equation = term.equation;
    eff.expression = term.expression.to_string();
    const std::string param = term_parameter_name(term);
    const auto it = res.augmented.find(param);
    if (it != res.augmented.end()) {
      eff.coefficient = it->second.value;
      eff.interval[0] = it->second.value - 1.96 * it->second.sigma_coloured;
      eff.interval[1] = it->second.value + 1.96 * it->second.sigma_coloured;
      eff.parameters[param] = it->second.value;
      eff.sigma[param] = it->second.sigma_coloured;
    }
    for (const auto& t : res.candidates) {
      if (t.name == "term" && t.entered && t.equation == term.equation && t.expression == eff.expression) {
        eff.alternatives = t.alternatives;
        for (const char* k : kScanParameters) {  // a scanned parameter with its 95 % interval
          for (const std::string suffix : {"", "_lo", "_hi"}) {
            const auto it = t.parameters.find(k + suffix);
            if (it != t.parameters.end()) eff.parameters[k + suffix] = it->second;
          }
        }
      }
      // Why each library effect was ruled out: its first trial (it was tried before any term).
      if (t.name == "term" || t.round != 1) continue;
      eff.ruled_out.emplace_back(t.name, t.reason);
    }
    res.effects.push_back(std::move(eff));
  }
  for (const auto& name : m.effect_names) {
    if (is_found_term(name)) continue;
    const CandidateSpec& spec = *effects::find_definition(name);
    if (spec.wideband()) continue;  // named by the wideband stage
    NamedEffect eff;
    eff.name = name;
    for (const auto& term : spec.terms) {
      const auto it = res.augmented.find(term.parameter);
      if (it == res.augmented.end()) continue;
      eff.parameters[term.parameter] = it->second.value;
      eff.sigma[term.parameter] = it->second.sigma_coloured;
    }
    for (const auto& t : res.candidates) {
      if (t.name != name || !t.entered) continue;
      if (spec.scan == effects::Scan::kDelay) eff.parameters[spec.scan_parameter()] = t.delay_s;
      eff.contradicts = t.contradicts;
      time_varying_parameters(m, wf.batch, wf.data, t, eff);  // rate or change time, for effects that change
    }
    res.effects.push_back(std::move(eff));
  }
}

/// Where the baseline structure's residual lives (a periodic component, a state dependence), each
/// test at the workflow's p_critical; and the descriptive energy shares of the manoeuvres, hovers
/// and heaviest windows. Returns the number of alarm tests run.
std::size_t locate(const UniformData& d, const DiscrepancyOptions& options, const Model& m,
                   const std::vector<VectorXd>& base_resid, const BatchRule& batch, const Folds& folds,
                   double p_critical, DiscrepancyResult& res) {
  const Segments seg = find_segments(d, options.segments);
  for (std::size_t e = 0; e < m.eqs.size(); ++e) {
    time_findings(m.eqs[e].output, base_resid[e] / m.eqs[e].scale, d, seg, options.window_s, res.located.time);
  }
  const Excitation ex = excitation_bank(d, options.excitation);
  res.located.excitation = ex.signals;
  if (ex.signals.empty()) {
    std::string names;
    for (const auto& n : options.excitation) names += (names.empty() ? "" : ", ") + n;
    res.located.note = "no location test: the data has no moving exogenous signal (" + names +
                       ") to tell the linear response to the manoeuvre from structure the model misses";
    return 0;
  }
  const double f_hi = options.processing.filter_order > 0 ? 0.8 * options.processing.cutoff_hz : 0.45 * d.rate_hz;
  std::size_t tests = 0;
  const LocationRule rule{p_critical, batch.min_block,       options.gust_band_hz, options.gust_band_alpha,
                          folds,      options.heldout_sigmas};
  for (std::size_t e = 0; e < m.eqs.size(); ++e) {
    // Not the actuator's own equation: its error on sampled data follows the recorded command's
    // sampling and latency, which the locator cannot tell from physics (with the command recorded,
    // 6 of 120 null generator records were `unexplained` there); a delay before the actuator is
    // tested in it by actuator_delay.
    if (e == kActuatorEq) continue;
    // The baseline structure without the effects that entered (it is what the gap starts from).
    const MatrixXd X = augmented_design(m.eqs[e], {});
    const LocationFrame frame(X, m.eqs[e].y, ex.Z);
    // Above the gust band, as every candidate: below it a periodic force cannot be told from a
    // side wind's random low-frequency force.
    frequency_peaks(frame, m.eqs[e].output, m.eqs[e].scale, d.rate_hz, options.gust_band_hz, f_hi, rule,
                    res.located.frequency);
    state_findings(frame, X, m.eqs[e].output, d, rule, res.located.state);
    tests += 2;
  }
  return tests;
}

/// Candidates that met every entry rule but whose signature failed (CandidateTrial::
/// signature_holds), and that no later round named: the structure their terms fit is located,
/// unexplained, once per candidate.
void signature_findings(const DiscrepancyOptions& options, DiscrepancyResult& res) {
  for (const auto& t : res.candidates) {
    if (t.signature_holds) continue;
    const auto named = [&](const auto& list) {
      return std::any_of(list.begin(), list.end(), [&](const auto& x) { return x.name == t.name; });
    };
    const bool listed = std::any_of(res.located.signature.begin(), res.located.signature.end(),
                                    [&](const SignatureFinding& f) { return f.candidate == t.name; });
    if (named(res.effects) || listed) continue;
    SignatureFinding f;
    f.candidate = t.name;
    for (const auto& [eq, F] : t.partial_f) {
      if (F >= options.partial_f) f.equations.push_back(eq);
    }
    f.note = t.name + "'s terms: " + t.signature_note;
    res.located.signature.push_back(std::move(f));
  }
}

/// The verdict and its one-line summary.
void judge(const CandidateTrial& gust_result, DiscrepancyResult& res) {
  // Verdict.
  const bool structure_found =
      !res.located.frequency.empty() || !res.located.state.empty() || !res.located.signature.empty();
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
    for (const auto& e : res.effects) {
      s << " " << e.name;
      if (!e.channel.empty()) {
        s << " " << e.channel << (e.against.empty() ? "" : " against " + e.against) << " " << fmt(e.coefficient) << " "
          << e.unit << " [" << fmt(e.interval[0]) << ", " << fmt(e.interval[1]) << "]";
      }
      if (e.name == "term") {
        s << " " << e.equation << " += " << fmt(e.coefficient) << " " << e.expression << " (a form outside the library";
        for (const char* k : kScanParameters) {
          const auto v = e.parameters.find(k), lo = e.parameters.find(k + std::string("_lo")),
                     hi = e.parameters.find(k + std::string("_hi"));
          if (v != e.parameters.end() && lo != e.parameters.end() && hi != e.parameters.end()) {
            s << "; " << k << " " << fmt(v->second) << " [" << fmt(lo->second) << ", " << fmt(hi->second) << "]";
          }
        }
        s << ")";
      }
      if (!e.contradicts.empty()) s << " (" << e.contradicts << ")";
    }
    for (const auto& pair : res.ambiguous) s << "; " << pair[0] << " and " << pair[1] << " explain the same thing";
    s << "; held-out gap " << fmt(res.gap_before) << " -> " << fmt(res.gap_after) << " in the identification band";
    for (std::size_t i = 1; i < res.gap_bands.size(); ++i) {
      const BandGap& b = res.gap_bands[i];
      std::string eqs;
      for (const auto& e : b.equations) eqs += (eqs.empty() ? "" : ", ") + e;
      s << ", " << fmt(b.before) << " -> " << fmt(b.after) << " in " << b.name << "'s band " << fmt(b.lo_hz) << "-"
        << fmt(b.hi_hz) << " Hz (" << eqs << (b.wideband ? ", wideband data" : "") << ")";
    }
    for (const auto& c : res.consistency) {
      s << "; " << c.effect << (c.same ? " the same in all " : " not the same in all ") << res.flights.size()
        << " flights (p " << fmt(c.p_value) << (c.same ? ")" : ", " + c.differs + " differs most)");
    }
    if (gust_result.entered) {
      s << " (lateral_gust is random: it has no regressor and leaves the gap as it is; its evidence is the "
           "residual spectrum)";
    }
  } else if (res.verdict == "unexplained") {
    s << "no candidate passes, but the residual has structure:";
    for (const auto& f : res.located.frequency) s << " " << f.output << " peak at " << fmt(f.f_hz) << " Hz;";
    for (const auto& f : res.located.state) s << " " << f.output << " depends nonlinearly on " << f.signal << ";";
    for (const auto& f : res.located.signature) {
      std::string eqs;
      for (const auto& e : f.equations) eqs += (eqs.empty() ? "" : ", ") + e;
      s << " " << (eqs.empty() ? std::string("the equations") : eqs) << ": " << f.note << ";";
    }
  } else {
    s << "nothing significant: no candidate passes and the residual shows no structure";
  }
  res.summary = s.str();
}

/// The model refit with the named effects (its effects: section), as --model-out writes it.
DerivativeModel augmented_model(const std::string& source, const DerivativeModel& model,
                                const std::vector<std::string>& inputs, const std::vector<std::string>& known,
                                const DiscrepancyResult& res) {
  // The augmented model.
  DerivativeModel am = model;
  am.name = model.name + "_augmented";
  am.source = "rig discrepancy " + source + " on " + model.name;
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
    const auto& spec = *effects::find_definition(name);
    for (const auto& term : spec.terms) {
      const auto it = res.augmented.find(term.parameter);
      if (it != res.augmented.end()) am.effects[name][term.parameter] = it->second.value;
    }
    const auto& given = model.effects.at(name);
    const std::string scanned = spec.scan_parameter();
    const bool refit_keeps_scan = spec.scan == effects::Scan::kDelay || spec.scan == effects::Scan::kChangeTime;
    if (refit_keeps_scan && given.count(scanned)) am.effects[name][scanned] = given.at(scanned);
    if (spec.stochastic()) am.effects[name] = given;
  }
  for (const auto& e : res.effects) {
    if (!e.channel.empty()) continue;  // a sensor error: the record was corrected, the model is not changed
    if (e.name == "term") {
      am.terms.push_back(
          Term{e.equation, TermExpression::parse(e.expression), e.coefficient, "rig discrepancy " + source});
    } else {
      am.effects[e.name] = e.parameters;
    }
  }
  for (auto& term : am.terms) {
    const auto it = res.augmented.find(term_parameter_name(term));
    if (it != res.augmented.end()) term.coefficient = it->second.value;
  }
  return am;
}

}  // namespace

namespace {

/// The library's candidates the options ask for (all when they name none), in the library's order.
std::vector<const CandidateSpec*> candidate_pool(const DiscrepancyOptions& options) {
  std::vector<const CandidateSpec*> pool;
  for (const auto& c : candidate_library()) {
    if (options.candidates.empty() ||
        std::find(options.candidates.begin(), options.candidates.end(), c.name) != options.candidates.end()) {
      pool.push_back(&c);
    }
  }
  return pool;
}

/// The run's alarm rule: each library trial is a test; the open-world search is one test per round
/// (Bonferroni over its families inside), however many of its trials are listed; plus the location
/// and compatibility tests (`other_tests`).
AlarmRule alarm_rule(const std::vector<CandidateTrial>& candidates, double p_critical, std::size_t other_tests) {
  std::size_t term_rounds = 0;
  for (const auto& t : candidates) {
    if (t.name == "term") term_rounds = std::max(term_rounds, t.round);
  }
  AlarmRule rule;
  rule.p_critical = p_critical;
  rule.tests = static_cast<std::size_t>(std::count_if(candidates.begin(), candidates.end(),
                                                      [](const CandidateTrial& t) { return t.name != "term"; })) +
               term_rounds + other_tests;
  rule.family_wise = static_cast<double>(rule.tests) * p_critical;
  return rule;
}

}  // namespace

DiscrepancyResult find_discrepancy(const FlightData& data, const DerivativeModel& model, const Vehicle& vehicle,
                                   const DiscrepancyOptions& options) {
  return find_discrepancy(std::vector<FlightData>{data}, model, vehicle, options);
}

DiscrepancyResult find_discrepancy(const std::vector<FlightData>& flights, const DerivativeModel& model,
                                   const Vehicle& vehicle, const DiscrepancyOptions& options) {
  check_request(model, options);
  if (flights.empty()) throw std::invalid_argument("discrepancy: no flight data");
  const bool pooled = flights.size() > 1;

  DiscrepancyResult res;
  res.model_name = model.name;
  const std::vector<std::string> inputs = options.inputs.empty() ? model.inputs : options.inputs;
  // Each flight prepared on its own (filter, derivatives, the applied command), then joined.
  std::vector<UniformData> prepared;
  std::vector<FlightData> aligned;  // each flight corrected by its data-compatibility stage
  for (const FlightData& recorded : flights) {
    check_flight_data(recorded, vehicle);
    check_excitation(recorded, state_names(model.structure), inputs);
    for (const auto& in : inputs) {
      if (!recorded.has(in))
        throw DataError(recorded.source, -1, -1, in, "the model's input " + in + " is not in the data");
    }
    const FlightData& data = aligned.emplace_back(compatibility_stage(recorded, model, vehicle, inputs, options, res));
    PreparedData prep = prepare(data, Structure::kLateral3, model.trim, vehicle.gravity_mps2, options.processing);
    add_applied_command(prep.filtered, options.command_latency_s);
    if (prep.filtered.size() < static_cast<Index>(50 * options.folds)) {
      char need[96];
      std::snprintf(need, sizeof need, ": need at least %zu (50 per fold, %.2f s at %.6g Hz)", 50 * options.folds,
                    static_cast<double>(50 * options.folds - 1) / options.processing.rate_hz,
                    options.processing.rate_hz);
      throw DataError(data.source, -1, -1, "",
                      std::to_string(prep.filtered.size()) + " samples are too few for " +
                          std::to_string(options.folds) + "-fold cross-validation" + need);
    }
    prepared.push_back(std::move(prep.filtered));
  }
  std::vector<std::pair<Index, Index>> rows;
  const UniformData d = join_flights(prepared, rows);
  prepared.clear();
  const FlightData& data = aligned.front();
  res.source = d.source;
  const Index n = d.size();
  res.rate_hz = d.rate_hz;
  res.cutoff_hz = options.processing.filter_order > 0 ? options.processing.cutoff_hz : 0.0;
  res.t_s = d.t_s;
  res.samples = static_cast<std::size_t>(n);
  res.folds = options.folds;

  // Baseline equations (the model's structure with the effects the model file carries).
  const auto equations = lateral_equations(Structure::kLateral3, inputs, vehicle);
  SearchScope scope;
  Model m = build_baseline(d, equations, model, vehicle, data.source, &scope.known, &scope.known_values);

  Workflow wf{options, vehicle, model, d, flight_folds(rows, options.folds), {}, 0.0, {}, {}};
  wf.batch.min_block = batch_min_block(options);
  wf.p_critical = alarm_p_critical(options);

  scope.pool = candidate_pool(options);
  const std::vector<std::string>& known = scope.known;
  const std::map<std::string, double>& known_values = scope.known_values;

  // Baseline fit and its held-out residuals; pooled flights weighted by their own noise levels.
  std::vector<VectorXd> base_resid;
  res.baseline = full_fit(m, wf.batch, &base_resid);
  if (pooled) {
    const auto level = weight_flights(m, base_resid, rows);
    for (std::size_t f = 0; f < flights.size(); ++f) {
      FlightEstimate fe;
      fe.source = flights[f].source;
      fe.samples = static_cast<std::size_t>(rows[f].second - rows[f].first);
      fe.start_s = d.t_s[rows[f].first];
      fe.end_s = d.t_s[rows[f].second - 1];
      for (std::size_t e = 0; e < m.eqs.size(); ++e) fe.noise[m.eqs[e].name] = level[f][e] / m.eqs[e].scale;
      res.flights.push_back(std::move(fe));
    }
    base_resid.clear();
    res.baseline = full_fit(m, wf.batch, &base_resid);
  }
  const std::vector<VectorXd> cv_before = heldout_residuals(m, wf.folds);
  test_given_terms(wf, m, res);

  stepwise_search(wf, scope.pool, known, m, res);
  std::vector<BandGap> wide_bands;
  if (!pooled) wideband_stage(wf, scope, data, equations, m, res, wide_bands);
  // The open world: what the library's named effects leave (none may be ambiguous).
  if (options.term_search && res.ambiguous.empty()) term_search(wf, inputs, m, res);

  // The augmented fit and the gap after.
  std::vector<VectorXd> aug_resid;
  res.augmented = full_fit(m, wf.batch, &aug_resid);
  const std::vector<VectorXd> cv_after = heldout_residuals(m, wf.folds);
  const CandidateTrial gust_result = gust_stage(wf, scope, m, aug_resid, res);
  name_effects(m, wf, res);
  if (gust_result.entered) {
    NamedEffect gust;
    gust.name = gust_result.name;
    gust.parameters = gust_result.parameters;
    gust.sigma = gust_result.sigma;
    res.effects.push_back(std::move(gust));
  }
  const std::size_t location_tests = locate(d, options, m, base_resid, wf.batch, wf.folds, wf.p_critical, res);
  signature_findings(options, res);
  const std::size_t compatibility_tests = sensor_findings(res);
  res.alarm_rule = alarm_rule(res.candidates, wf.p_critical, location_tests + compatibility_tests);
  gap_table(d, model, options, known_values, m, cv_before, cv_after, res);
  gap_bands(d, options, m, cv_before, cv_after, std::move(wide_bands), res);
  if (pooled) flight_consistency(m, wf.batch, rows, options.consistency_alpha, res);
  judge(gust_result, res);
  res.augmented_model = augmented_model(res.source, model, inputs, known, res);
  return res;
}

}  // namespace nimble::ident
