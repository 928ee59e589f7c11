#include "ident/identify.h"

#include "ident/output_error.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "ident/data_check.h"

namespace nimble::ident {
namespace {

const std::vector<std::string> kInputOrder{"delta_f", "delta_t", "delta_d", "delta_w"};

std::vector<std::string> equation_letters(Structure s) {
  if (s == Structure::kLateral3) return {"L", "Y"};
  if (s == Structure::kLateral4) return {"L", "N", "Y"};
  if (is_blackbox(s)) return state_names(s);  // one equation per row of A and B, named by its state
  throw std::invalid_argument("identification supports lateral3, lateral4, blackbox3 and blackbox4, not " +
                              to_string(s));
}

bool is_input(const std::string& name) {
  return std::find(kInputOrder.begin(), kInputOrder.end(), name) != kInputOrder.end();
}

void require_channels(const FlightData& data, const std::vector<std::string>& names, const std::string& why) {
  std::vector<std::string> missing;
  for (const auto& n : names) {
    if (!data.has(n)) missing.push_back(n);
  }
  if (missing.empty()) return;
  std::string list;
  for (const auto& m : missing) list += (list.empty() ? "" : ", ") + m;
  throw DataError(data.source, -1, -1, missing.front(),
                  why + " needs column" + (missing.size() > 1 ? "s " : " ") + list);
}

std::vector<TimeRange> runs(const UniformData& data, const std::vector<bool>& mask, double min_length_s) {
  std::vector<TimeRange> out;
  const Eigen::Index n = data.size();
  Eigen::Index k = 0;
  while (k < n) {
    if (!mask[static_cast<std::size_t>(k)]) {
      ++k;
      continue;
    }
    const Eigen::Index start = k;
    while (k < n && mask[static_cast<std::size_t>(k)]) ++k;
    const TimeRange r{data.t_s[start], data.t_s[k - 1]};
    if (r.end_s - r.start_s >= min_length_s) out.push_back(r);
  }
  return out;
}

}  // namespace

Segments find_segments(const UniformData& data, const SegmentOptions& options) {
  for (const auto* list : {&options.hover, &options.manoeuvre}) {
    for (const auto& r : *list) {
      if (!(r.end_s > r.start_s)) {
        throw std::invalid_argument("segment " + std::to_string(r.start_s) + ":" + std::to_string(r.end_s) +
                                    " s: end must be after start");
      }
    }
  }
  Segments s;
  const Eigen::Index samples = data.size();
  if (samples > 0) {
    // A range must overlap the data: one beyond it would give statistics of nothing (NaN).
    const double first = data.t_s[0], last = data.t_s[samples - 1];
    for (const auto* list : {&options.hover, &options.manoeuvre}) {
      for (const auto& r : *list) {
        if (r.end_s < first || r.start_s > last) {
          char buf[160];
          std::snprintf(buf, sizeof buf, "segment %g:%g s lies outside the data (%.3f to %.3f s)", r.start_s, r.end_s,
                        first, last);
          throw std::invalid_argument(buf);
        }
      }
    }
  }
  if (!options.hover.empty() || !options.manoeuvre.empty()) {
    s.hover = options.hover;
    s.manoeuvre = options.manoeuvre;
    s.how = "time ranges";
    return s;
  }
  const Eigen::Index n = data.size();
  if (!data.has("phi_sp") || n == 0) {
    if (n > 0) s.manoeuvre.push_back({data.t_s[0], data.t_s[n - 1]});
    s.how = "whole record";
    return s;
  }
  const Eigen::VectorXd& sp = data.at("phi_sp");
  const Eigen::Index margin = static_cast<Eigen::Index>(std::ceil(options.margin_s * data.rate_hz));
  std::vector<bool> active(static_cast<std::size_t>(n), false);
  for (Eigen::Index k = 0; k < n; ++k) {
    if (std::fabs(sp[k]) <= options.active_threshold_rad) continue;
    const Eigen::Index lo = std::max<Eigen::Index>(0, k - margin);
    const Eigen::Index hi = std::min<Eigen::Index>(n - 1, k + margin);
    for (Eigen::Index j = lo; j <= hi; ++j) active[static_cast<std::size_t>(j)] = true;
  }
  std::vector<bool> quiet(active.size());
  for (std::size_t k = 0; k < active.size(); ++k) quiet[k] = !active[k];
  s.manoeuvre = runs(data, active, options.min_length_s);
  s.hover = runs(data, quiet, options.min_length_s);
  s.how = "|phi_sp| activity";
  return s;
}

std::vector<std::pair<Eigen::Index, Eigen::Index>> sample_ranges(const UniformData& data,
                                                                 const std::vector<TimeRange>& ranges) {
  std::vector<std::pair<Eigen::Index, Eigen::Index>> out;
  const Eigen::Index n = data.size();
  if (n == 0) return out;
  const double t0 = data.t_s[0];
  for (const auto& r : ranges) {
    const Eigen::Index a =
        std::clamp<Eigen::Index>(static_cast<Eigen::Index>(std::ceil((r.start_s - t0) * data.rate_hz - 1e-9)), 0, n);
    const Eigen::Index b =
        std::clamp<Eigen::Index>(static_cast<Eigen::Index>(std::floor((r.end_s - t0) * data.rate_hz + 1e-9)) + 1, a, n);
    if (b > a) out.push_back({a, b});
  }
  return out;
}

PreparedData prepare(const FlightData& data, Structure structure, const Trim& trim, double gravity_mps2,
                     const ProcessingOptions& options) {
  const std::vector<std::string>& states = state_names(structure);
  require_channels(data, states, "structure " + to_string(structure));
  PreparedData out;
  out.raw = resample_uniform(data, options.rate_hz, options.interpolation);
  out.filtered = lowpass_filtered(out.raw, options);
  UniformData& f = out.filtered;
  for (const auto& s : states) f.signals[s + "_dot"] = differentiate(f.at(s), f.rate_hz);
  if (structure == Structure::kLateral3 || structure == Structure::kLateral4) {
    Eigen::VectorXd star = f.at("v_dot") - trim.w0_mps * f.at("p") -
                           gravity_mps2 * std::cos(trim.theta0_rad) * std::cos(trim.phi0_rad) * f.at("phi");
    if (structure == Structure::kLateral4) star += trim.u0_mps * f.at("r");
    f.signals["v_dot_star"] = std::move(star);
  }
  return out;
}

bool input_excited(const FlightData& data, const std::string& name, double* std_out) {
  const Channel& c = data.at(name);
  double mean = 0.0, ss = 0.0;
  for (double x : c.values) mean += x;
  mean /= std::max<std::size_t>(1, c.values.size());
  for (double x : c.values) ss += (x - mean) * (x - mean);
  const double sd = std::sqrt(ss / std::max<std::size_t>(1, c.values.size()));
  if (std_out) *std_out = sd;
  const double floor = (name == "delta_d" || name == "delta_w") ? kServoExcitationFloorRad : 0.0;
  return sd > floor;
}

std::vector<std::string> default_inputs(const FlightData& data, std::vector<std::string>* left_out) {
  std::vector<std::string> out{"delta_f", "delta_t"};
  for (const char* extra : {"delta_d", "delta_w"}) {
    if (!data.has(extra)) continue;
    double sd = 0.0;
    if (input_excited(data, extra, &sd)) {
      out.push_back(extra);
    } else if (left_out) {
      char buf[200];
      std::snprintf(buf, sizeof buf, "%s left out: standard deviation %.3g rad, below the excitation floor %.3g rad",
                    extra, sd, kServoExcitationFloorRad);
      left_out->push_back(buf);
    }
  }
  return out;
}

std::string parameter_name(const std::string& letter, const std::string& regressor) {
  if (regressor == "p" || regressor == "r" || regressor == "v" || regressor == "q" || regressor == "u" ||
      regressor == "w") {
    return letter + regressor;
  }
  if (is_input(regressor)) return letter + "_" + input_suffix(regressor);
  return letter + "_" + regressor;
}

std::vector<Equation> lateral_equations(Structure structure, const std::vector<std::string>& inputs,
                                        const Vehicle& vehicle) {
  const std::vector<std::string> letters = equation_letters(structure);
  for (const auto& in : inputs) {
    if (!is_input(in)) throw std::invalid_argument("unknown input '" + in + "' (delta_f, delta_t, delta_d, delta_w)");
  }
  std::vector<Equation> eqs;
  if (is_blackbox(structure)) {
    // Thesis Eq C.32-C.35 / C.38-C.40: each state derivative on every state and input, the
    // parameters the entries of A and B themselves; no constant moves to the left-hand side.
    std::vector<std::string> regressors = state_names(structure);
    for (const auto& in : inputs) regressors.push_back(in);
    for (const auto& row : state_names(structure)) {
      Equation eq;
      eq.name = row;
      eq.dependent = row + "_dot";
      eq.scale = 1.0;
      eq.regressors = regressors;
      for (const auto& column : state_names(structure)) eq.parameters.push_back(blackbox_a_name(row, column));
      for (const auto& in : inputs) eq.parameters.push_back(blackbox_b_name(row, in));
      eqs.push_back(std::move(eq));
    }
    return eqs;
  }
  std::vector<std::string> regressors =
      structure == Structure::kLateral4 ? std::vector<std::string>{"p", "r", "v"} : std::vector<std::string>{"p", "v"};
  for (const auto& in : inputs) regressors.push_back(in);
  for (const auto& letter : letters) {
    Equation eq;
    eq.name = letter;
    eq.regressors = regressors;
    if (letter == "L") {
      eq.dependent = "p_dot";
      eq.scale = vehicle.Ic() / vehicle.Izz_kgm2;
    } else if (letter == "N") {
      eq.dependent = "r_dot";
      eq.scale = vehicle.Ic() / vehicle.Ixx_kgm2;
    } else {
      eq.dependent = "v_dot_star";
      eq.scale = vehicle.mass_kg;
    }
    for (const auto& r : regressors) eq.parameters.push_back(parameter_name(letter, r));
    eqs.push_back(std::move(eq));
  }
  return eqs;
}

std::string default_vehicle_file() { return NIMBLE_DEFAULT_VEHICLE; }

std::size_t whiteness_lag_step(std::size_t requested, const ProcessingOptions& processing) {
  if (requested > 0) return requested;
  if (processing.filter_order <= 0) return 1;
  return std::max<std::size_t>(
      1, static_cast<std::size_t>(std::lround(processing.rate_hz / (2.0 * processing.cutoff_hz))));
}

std::size_t coloured_lags(std::size_t requested, const ProcessingOptions& processing) {
  return requested > 0 ? requested : 4 * whiteness_lag_step(0, processing);
}

std::vector<StatePsd> state_psds(const UniformData& raw, const std::vector<std::string>& states,
                                 const Segments& segments, double segment_s) {
  const std::size_t seg = std::max<std::size_t>(8, static_cast<std::size_t>(std::lround(segment_s * raw.rate_hz)));
  const auto hover = sample_ranges(raw, segments.hover);
  const auto man = sample_ranges(raw, segments.manoeuvre);
  std::vector<StatePsd> out;
  for (const auto& s : states) {
    StatePsd p;
    p.state = s;
    p.unit = channel_spec(s).unit;
    const Eigen::VectorXd& x = raw.at(s);
    // A part too short for one segment of 8 samples has no PSD.
    if (!hover.empty()) {
      try {
        p.hover = welch(x, raw.rate_hz, seg, hover);
        p.has_hover = p.hover.segments > 0;
      } catch (const std::invalid_argument&) {
        p.has_hover = false;
      }
    }
    if (!man.empty()) {
      try {
        p.manoeuvre = welch(x, raw.rate_hz, seg, man);
        p.has_manoeuvre = p.manoeuvre.segments > 0;
      } catch (const std::invalid_argument&) {
        p.has_manoeuvre = false;
      }
    }
    out.push_back(std::move(p));
  }
  return out;
}

std::string term_signal_column(const Term& term) { return "term:" + term.expression.to_string(); }

Eigen::VectorXd term_column(const UniformData& data, const Term& term) {
  const std::vector<std::string> names = term.expression.signals();
  std::vector<std::vector<double>> values;
  for (const auto& name : names) {
    const Eigen::VectorXd& x = data.at(name);
    values.emplace_back(x.data(), x.data() + x.size());
  }
  std::vector<const std::vector<double>*> columns;
  for (const auto& v : values) columns.push_back(&v);
  std::vector<double> out = evaluate_along(term.expression, names, columns, 1.0 / data.rate_hz);
  if (names.empty())
    out.assign(static_cast<std::size_t>(data.size()), TermProgram(term.expression, {}).evaluate(nullptr));
  return Eigen::Map<const Eigen::VectorXd>(out.data(), static_cast<Eigen::Index>(out.size()));
}

void add_term_column(UniformData& data, const Term& term) {
  data.signals[term_signal_column(term)] = term_column(data, term);
}

namespace {

/// The identification's inputs: those asked for, or the excited ones; in the canonical order, each once.
void choose_inputs(const FlightData& data, const IdentOptions& options, IdentResult& res) {
  res.inputs = options.inputs.empty() ? default_inputs(data, &res.inputs_left_out) : options.inputs;
  std::vector<std::string> ordered;
  for (const auto& name : kInputOrder) {
    if (std::find(res.inputs.begin(), res.inputs.end(), name) != res.inputs.end()) ordered.push_back(name);
  }
  for (const auto& in : res.inputs) {
    if (!is_input(in)) throw std::invalid_argument("unknown input '" + in + "' (delta_f, delta_t, delta_d, delta_w)");
  }
  res.inputs = ordered;
  if (res.inputs.empty()) throw std::invalid_argument("identification needs at least one input");
  require_channels(data, res.inputs, "input list");
}

/// The structure's equations with the extra regressors and terms; throws if the data are too few
/// for their parameters.
std::vector<Equation> equations_for(const FlightData& data, const Vehicle& vehicle,
                                    const std::vector<std::string>& inputs, const IdentOptions& options) {
  std::vector<Equation> equations = lateral_equations(options.structure, inputs, vehicle);
  for (const auto& extra : options.extra_regressors) {
    auto it =
        std::find_if(equations.begin(), equations.end(), [&](const Equation& e) { return e.name == extra.equation; });
    if (it == equations.end()) {
      throw std::invalid_argument("extra regressor '" + extra.signal + "': structure " + to_string(options.structure) +
                                  " has no equation '" + extra.equation + "'");
    }
    it->regressors.push_back(extra.signal);
    it->parameters.push_back(extra.equation + "_" + extra.signal);
  }
  for (const auto& term : options.terms) {
    auto it =
        std::find_if(equations.begin(), equations.end(), [&](const Equation& e) { return e.name == term.equation; });
    if (it == equations.end()) {
      throw std::invalid_argument("term '" + term_parameter_name(term) + "' (" + term.where + "): structure " +
                                  to_string(options.structure) + " has no equation '" + term.equation + "'");
    }
    require_channels(data, term.expression.signals(), "term " + term_parameter_name(term));
    it->regressors.push_back(term_signal_column(term));
    it->parameters.push_back(term_parameter_name(term));
  }
  std::size_t n_params = 0;
  for (const auto& eq : equations) n_params += eq.regressors.size();
  const std::size_t rows = data.min_samples();
  if (rows < 10 * n_params) {
    throw DataError(data.source, -1, -1, "",
                    std::to_string(rows) + " samples are too few for " + to_string(options.structure) + " with " +
                        std::to_string(n_params) + " parameters: need at least " + std::to_string(10 * n_params) +
                        " (10 per parameter)");
  }
  return equations;
}

/// Each equation's fit: measured against estimated, its metrics and its residual's whiteness.
void fit_outputs(const IdentOptions& options, IdentResult& res) {
  const std::size_t lag_step = whiteness_lag_step(options.whiteness_lag_step, options.processing);
  for (const auto& eq : res.regression.equations) {
    OutputFit fit;
    fit.output = eq.equation.dependent;
    const std::string& y = eq.equation.dependent;
    fit.unit = (y == "v_dot_star" || y == "v_dot") ? "m/s^2" : y == "phi_dot" ? "rad/s" : "rad/s^2";
    fit.measured = eq.y / eq.equation.scale;
    fit.estimated = eq.fitted / eq.equation.scale;
    fit.metrics = fit_metrics(fit.measured, fit.estimated, static_cast<int>(eq.theta.size()));
    fit.whiteness =
        residual_whiteness(fit.measured - fit.estimated, res.data.filtered.rate_hz, options.whiteness_lags, lag_step);
    res.fits.push_back(std::move(fit));
  }
}

/// The identified linear model, its state space, eigenvalues and modes.
void build_model(const FlightData& data, const Vehicle& vehicle, const std::string& vehicle_file,
                 const IdentOptions& options, IdentResult& res) {
  DerivativeModel& m = res.model;
  const std::string stem = std::filesystem::path(data.source).stem().string();
  m.name = options.model_name.empty() ? (stem.empty() ? "identified" : stem) + "_" + to_string(options.structure) +
                                            "_" + to_string(options.method)
                                      : options.model_name;
  m.source = "rig identify " + data.source + " (" + to_string(options.method) + ")";
  m.vehicle_file = vehicle_file;
  m.structure = options.structure;
  m.coupling = RollYawCoupling::kDecoupled;
  m.inputs = res.inputs;
  m.trim = options.trim;
  if (!has_yaw_rate(m.structure)) m.trim.u0_mps = 0.0;  // not part of a three-state model
  std::vector<std::string> model_names = stability_derivative_names(m.structure);
  for (const auto& in : m.inputs) {
    for (const auto& n : control_derivative_names(m.structure, in)) model_names.push_back(n);
  }
  for (const auto& n : model_names) {
    const ParameterEstimate& e = res.parameters.at(n);
    m.derivatives[n] = e.value;
    m.published_sigma[n] = e.sigma;
  }
  m.terms = options.terms;
  for (auto& term : m.terms) term.coefficient = res.parameters.at(term_parameter_name(term)).value;
  res.state_space = build_state_space(m, vehicle);
  res.eigenvalues = sorted_eigenvalues(res.state_space.A);
  res.modes = analyse_modes(res.state_space, vehicle);
  m.published_eigenvalues = res.eigenvalues;
}

/// The states' PSDs in hover and in the manoeuvres; a note for a part with none, saying what it needs.
void add_state_psds(const IdentOptions& options, IdentResult& res) {
  res.segments = find_segments(res.data.raw, options.segments);
  res.psd = state_psds(res.data.raw, state_names(options.structure), res.segments, options.psd_segment_s);
  // A part with no PSD: say what it needs.
  bool any_hover = false, any_manoeuvre = false;
  for (const auto& p : res.psd) {
    any_hover = any_hover || p.has_hover;
    any_manoeuvre = any_manoeuvre || p.has_manoeuvre;
  }
  const UniformData& raw = res.data.raw;
  const double length_s = raw.size() > 1 ? raw.t_s[raw.size() - 1] - raw.t_s[0] : 0.0;
  for (const auto& [part, have] : {std::pair<const char*, bool>{"hover", any_hover}, {"manoeuvre", any_manoeuvre}}) {
    if (have) continue;
    char buf[320];
    if (res.segments.how == "|phi_sp| activity") {
      std::snprintf(buf, sizeof buf,
                    "%s PSD skipped: needs a %s part of at least %.3g s (|phi_sp| %s %.3g rad, %.3g s beside each "
                    "manoeuvre), the record (%.2f s) has none",
                    part, part, options.segments.min_length_s, std::string(part) == "hover" ? "<=" : ">",
                    options.segments.active_threshold_rad, options.segments.margin_s, length_s);
    } else if (res.segments.how == "whole record") {
      std::snprintf(buf, sizeof buf,
                    "%s PSD skipped: without phi_sp the whole record (%.2f s) is the manoeuvre; "
                    "--hover A:B gives a hover part",
                    part, length_s);
    } else {
      std::snprintf(buf, sizeof buf, "%s PSD skipped: no %s range given, or none holds a segment of 8 samples", part,
                    part);
    }
    res.notes.push_back(buf);
  }
}

/// Replaces the equation error's estimates in `res.regression` by output error's (started from
/// them), equation by equation; the fitted derivatives and residuals are those of the new values.
void refine_by_output_error(const IdentOptions& options, const Vehicle& vehicle, const std::vector<Equation>& equations,
                            IdentResult& res) {
  std::map<std::string, double> start;
  for (const auto& [name, est] : res.regression.parameters()) start[name] = est.value;
  OutputErrorOptions oe = options.output_error;
  if (oe.coloured_block == 0) {
    oe.coloured_block = static_cast<Eigen::Index>(4 * coloured_lags(options.coloured_lags, options.processing));
  }
  const OutputErrorResult r = output_error(res.data.filtered, equations, options.trim, vehicle.gravity_mps2, start, oe);
  RegressionResult& g = res.regression;
  g.method = Method::kOutputError;
  g.covariance = r.covariance;
  g.covariance_coloured = r.covariance_coloured;
  Eigen::Index off = 0;
  for (auto& eq : g.equations) {
    const Eigen::Index k = eq.theta.size();
    eq.theta = r.theta.segment(off, k);
    eq.covariance = r.covariance.block(off, off, k, k);
    eq.sigma = eq.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
    eq.sigma_coloured = r.covariance_coloured.block(off, off, k, k).diagonal().cwiseMax(0.0).cwiseSqrt();
    eq.correlation = correlation_of(eq.covariance);
    Eigen::MatrixXd X(eq.y.size(), k);
    for (Eigen::Index j = 0; j < k; ++j)
      X.col(j) = res.data.filtered.at(eq.equation.regressors[static_cast<std::size_t>(j)]);
    eq.fitted = X * eq.theta;
    eq.residual = eq.y - eq.fitted;
    eq.residual_variance = eq.residual.squaredNorm() / static_cast<double>(std::max<Eigen::Index>(1, eq.y.size() - k));
    off += k;
  }
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "output error: %d segments of %.3g s, %d iterations (%s), weighted cost %.4g -> %.4g from the "
                "equation error's values; constant accelerations fitted beside: p %.3g rad/s^2, v %.3g m/s^2",
                r.segments, oe.segment_s, r.iterations, r.converged ? "converged" : "not converged", r.cost_start,
                r.cost, r.bias_p, r.bias_v);
  res.notes.push_back(buf);
}

}  // namespace

IdentResult identify(const FlightData& data, const Vehicle& vehicle, const std::string& vehicle_file,
                     const IdentOptions& options) {
  if (!(options.wls_window_s > 0.0)) throw std::invalid_argument("WLS window must be > 0 s");
  if (options.method == Method::kOutputError && options.structure != Structure::kLateral3) {
    throw std::invalid_argument("output error: the lateral3 structure only (lateral4's r equation is not simulated)");
  }
  check_flight_data(data, vehicle);
  IdentResult res;
  res.source = data.source;
  res.options = options;
  res.vehicle = vehicle;
  choose_inputs(data, options, res);
  std::vector<Equation> equations = equations_for(data, vehicle, res.inputs, options);
  check_excitation(data, state_names(options.structure), res.inputs);

  res.data = prepare(data, options.structure, options.trim, vehicle.gravity_mps2, options.processing);
  if (options.add_signals) options.add_signals(res.data.filtered);
  for (const auto& term : options.terms) add_term_column(res.data.filtered, term);

  WlsOptions wls;
  wls.variance_window = static_cast<Eigen::Index>(std::lround(options.wls_window_s * options.processing.rate_hz));
  wls.cross_equation = options.wls_cross_equation;
  CovarianceOptions cov;
  cov.correlation_lags = static_cast<Eigen::Index>(coloured_lags(options.coloured_lags, options.processing));
  res.regression = estimate(res.data.filtered.signals, equations, options.method, wls, cov);
  if (options.method == Method::kOutputError) refine_by_output_error(options, vehicle, equations, res);
  res.parameters = res.regression.parameters();
  res.parameter_order = res.regression.parameter_names;
  res.correlated = correlated_pairs(res.regression, options.correlation_threshold);

  fit_outputs(options, res);
  build_model(data, vehicle, vehicle_file, options, res);

  if (!res.fits.empty() && !res.fits.front().whiteness.tested) res.notes.push_back(res.fits.front().whiteness.note);

  add_state_psds(options, res);
  return res;
}

}  // namespace nimble::ident
