// The discrepancy workflow (discrepancy/discrepancy.h), part: the equations of the baseline model and the regressor columns of each candidate
// effect on the prepared data.

#include "discrepancy/discrepancy_parts.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "core/chi_square.h"
#include "ident/metrics.h"
#include "ident/spectrum.h"
#include "core/term_expression.h"

namespace nimble::ident::discrepancy_parts {

// ---------------------------------------------------------------------------------------
// The candidate library.

// The library is the registry's effects (effects/registry.h); the regressor columns of each are
// computed in candidate_columns().

/// A regressor column is excited when its standard deviation reaches this fraction of its
/// root mean square plus an absolute floor: a column that is (nearly) constant cannot be
/// told from the other regressors (except the intercept of sensor_bias, which is constant
/// by design). The floors are 10 resolution steps of the rig's actuator interface for the
/// inputs (the servos: kServoExcitationFloorRad, as rig identify uses) and 1e-9 otherwise.
double excitation_floor(const std::string& channel) {
  if (channel == "delta_d" || channel == "delta_w") return kServoExcitationFloorRad;
  if (channel == "delta_t") return 0.1;
  if (channel == "delta_f") return 0.1;
  return 1e-9;
}

// ---------------------------------------------------------------------------------------
// Building the equations and candidate columns.

Folds make_folds(Index n, std::size_t k) {
  Folds folds;
  for (std::size_t i = 0; i < k; ++i) {
    const Index a = static_cast<Index>(static_cast<double>(n) * static_cast<double>(i) / static_cast<double>(k));
    const Index b = static_cast<Index>(static_cast<double>(n) * static_cast<double>(i + 1) / static_cast<double>(k));
    folds.push_back({a, b});
  }
  return folds;
}

VectorXd delayed(const VectorXd& x, Index k) {
  VectorXd out(x.size());
  for (Index i = 0; i < x.size(); ++i) out[i] = x[std::max<Index>(0, i - k)];
  return out;
}

/// The command as the actuator receives it: delta_f_cmd late by the command path's known
/// latency (DiscrepancyOptions::command_latency_s, rounded to samples), as signal
/// "delta_f_cmd_applied". The actuator equation and its delay candidate use it, so that a
/// named actuator_delay is the delay beyond that latency.
void add_applied_command(UniformData& d, double latency_s) {
  if (!d.has("delta_f_cmd")) return;
  d.signals["delta_f_cmd_applied"] = delayed(d.at("delta_f_cmd"), std::lround(latency_s * d.rate_hz));
}

bool excited(const VectorXd& x, const std::string& channel) {
  const double mean = x.mean();
  const double sd = std::sqrt((x.array() - mean).square().mean());
  return sd >= excitation_floor(channel) && sd >= 1e-6 * std::sqrt(x.squaredNorm() / static_cast<double>(x.size()));
}

bool has_actuator_equation(const UniformData& d) {
  return d.has("delta_f_cmd_applied") && d.has("delta_f") && excited(d.at("delta_f_cmd_applied"), "delta_f");
}

/// A column of form kTerm on the prepared data: the term with the trim's u0 and w0 put in,
/// evaluated as the identification evaluates a model's terms (term_column()).
VectorXd term_column_of(const CandidateTerm& c, const UniformData& d, const Trim& trim) {
  return term_column(d, Term{c.equation, TermExpression::parse(effects::column_term(c, trim.u0_mps, trim.w0_mps)), 1.0,
                             "effect column " + c.parameter});
}

/// The columns of candidate `spec` on the prepared data (`scan`: delay in samples of a delayed
/// input, sample of the change of an input after a change), each computed as its form says
/// (effects/effect.h). A harmonic column has no form on these data: the wideband stage makes
/// it (harmonic_columns()).
std::vector<Addition> candidate_columns(const CandidateSpec& spec, const UniformData& d, const Trim& trim, double g,
                                        Index scan) {
  using effects::ColumnForm;
  const Index n = d.size();
  std::vector<Addition> out;
  auto add = [&](std::size_t eq, const std::string& name, VectorXd c) {
    for (auto& a : out) {
      if (a.eq == eq) {
        a.names.push_back(name);
        a.cols.push_back(std::move(c));
        return;
      }
    }
    out.push_back({eq, {name}, {std::move(c)}});
  };
  for (const CandidateTerm& c : spec.terms) {
    const bool actuator = c.equation == "F";
    if (actuator && !has_actuator_equation(d)) continue;
    const std::size_t eq = actuator ? kActuatorEq : c.equation == "L" ? 0 : 1;
    switch (c.form) {
      case ColumnForm::kTerm: add(eq, c.parameter, term_column_of(c, d, trim)); break;
      case ColumnForm::kGravityResidual: {
        const auto& phi = d.at("phi");
        add(eq, c.parameter, (g * std::cos(trim.theta0_rad) * (phi.array().sin() - phi.array())).matrix());
        break;
      }
      case ColumnForm::kDelayedInput: {
        const auto& x = d.at(actuator ? "delta_f_cmd_applied" : "delta_f");
        add(eq, c.parameter, delayed(x, scan) - x);
        break;
      }
      case ColumnForm::kInputTimesTime: add(eq, c.parameter, drift_time(d).cwiseProduct(d.at("delta_f"))); break;
      case ColumnForm::kInputAfterChange: {
        VectorXd x = d.at("delta_f");
        x.head(std::clamp<Index>(scan, 0, n)).setZero();
        add(eq, c.parameter, x);
        break;
      }
      case ColumnForm::kHarmonic: throw std::logic_error("candidate " + spec.name + ": harmonic columns have no scan");
    }
  }
  if (out.empty() && !spec.terms.empty()) throw std::logic_error("no columns for candidate " + spec.name);
  return out;
}

/// The columns of `eq` with `adds` (for this equation) appended.
MatrixXd augmented_design(const Eq& eq, const std::vector<Addition>& adds) {
  std::vector<VectorXd> cols = eq.cols;
  for (const auto& a : adds) {
    for (const auto& c : a.cols) cols.push_back(eq.w.size() ? VectorXd(c.cwiseProduct(eq.w)) : c);
  }
  return design(cols);
}

/// sin and cos of h 2 pi f t, h = 1 .. harmonics, in every equation.
std::vector<Addition> harmonic_columns(const VectorXd& t_s, double f_hz, int harmonics, const Model& m) {
  std::vector<Addition> out;
  for (std::size_t e = 0; e < m.eqs.size(); ++e) {
    if (m.eqs[e].name == "F") continue;  // a force or moment, not an actuator input
    Addition a;
    a.eq = e;
    for (int h = 1; h <= harmonics; ++h) {
      const VectorXd arg = (2.0 * M_PI * h * f_hz) * t_s;
      a.names.push_back(m.eqs[e].name + "_sin" + std::to_string(h));
      a.cols.push_back(arg.array().sin().matrix());
      a.names.push_back(m.eqs[e].name + "_cos" + std::to_string(h));
      a.cols.push_back(arg.array().cos().matrix());
    }
    out.push_back(std::move(a));
  }
  return out;
}

/// Prediction of equation `eq` (scaled as eq.y) by the model as given: its own derivatives,
/// the values of the effects its file carries, and the actuator of the options.
VectorXd given_prediction(const Eq& eq, const DerivativeModel& model, const std::map<std::string, double>& known_values,
                          const DiscrepancyOptions& options) {
  VectorXd out = VectorXd::Zero(eq.y.size());
  for (std::size_t j = 0; j < eq.names.size(); ++j) {
    const auto it = model.derivatives.find(eq.names[j]);
    const auto fx = known_values.find(eq.names[j]);
    if (eq.names[j] == "F_f") {
      out -= options.actuator_pole_radps * eq.cols[j];
    } else if (eq.names[j] == "F_cmd") {
      out += options.actuator_gain * eq.cols[j];
    } else if (it != model.derivatives.end()) {
      out += it->second * eq.cols[j];
    } else if (fx != known_values.end()) {
      out += fx->second * eq.cols[j];
    }
  }
  return out;
}

/// The model's regression equations on `d`, with the columns of the effects the model file
/// carries (an earlier analysis named them): refit with the derivatives, not tried again.
/// Effects without a column on `d` (flapping forcing on low-passed data) are only listed.
Model build_baseline(const UniformData& d, const std::vector<Equation>& equations, const DerivativeModel& model,
                     const Vehicle& vehicle, const std::string& source, std::vector<std::string>* known,
                     std::map<std::string, double>* known_values) {
  Model m;
  for (const auto& eq : equations) {
    Eq e;
    e.name = eq.name;
    e.output = eq.dependent;
    e.unit = eq.dependent == "v_dot_star" ? "m/s^2" : "rad/s^2";
    e.scale = eq.scale;
    e.y = eq.scale * d.at(eq.dependent);
    for (std::size_t j = 0; j < eq.regressors.size(); ++j) {
      e.names.push_back(eq.parameters[j]);
      e.cols.push_back(d.at(eq.regressors[j]));
    }
    m.eqs.push_back(std::move(e));
  }
  if (has_actuator_equation(d)) {
    // Eq 33 refit: delta_f_dot = F_f delta_f + F_cmd delta_f_cmd (the model as given has
    // F_f = -actuator_pole_radps, F_cmd = actuator_gain: DiscrepancyOptions).
    Eq e;
    e.name = "F";
    e.output = "delta_f_dot";
    e.unit = "rad/s^2";
    e.y = differentiate(d.at("delta_f"), d.rate_hz);
    e.names = {"F_f", "F_cmd"};
    e.cols = {d.at("delta_f"), d.at("delta_f_cmd_applied")};
    m.eqs.push_back(std::move(e));
  }
  m.added.resize(m.eqs.size());
  for (const auto& [name, params] : model.effects) {
    const CandidateSpec* spec = effects::find_definition(name);
    if (spec == nullptr) throw std::invalid_argument("the model's effect " + name + " is not one the registry knows");
    if (known) known->push_back(name);
    if (known_values) {
      for (const auto& [key, value] : params) (*known_values)[key] = value;
    }
    if (spec->wideband()) continue;
    for (const auto& need : spec->needs) {
      if (!d.has(need)) {
        throw DataError(source, -1, -1, need, "the model's effect " + name + " needs " + need + ", not in the data");
      }
    }
    for (auto& add : candidate_columns(*spec, d, model.trim, vehicle.gravity_mps2, scan_index(*spec, params, d))) {
      for (std::size_t j = 0; j < add.names.size(); ++j) {
        m.eqs[add.eq].names.push_back(add.names[j]);
        m.eqs[add.eq].cols.push_back(std::move(add.cols[j]));
      }
    }
  }
  // The model's generic terms (terms:), part of the model as its effects are: refit, not tried.
  for (const auto& term : model.terms) {
    const auto eq = std::find_if(m.eqs.begin(), m.eqs.end(), [&](const Eq& e) { return e.name == term.equation; });
    if (eq == m.eqs.end()) continue;
    for (const auto& s : term.expression.signals()) {
      if (!d.has(s)) {
        throw DataError(source, -1, -1, s,
                        "the model's term " + term_parameter_name(term) + " needs " + s + ", not in the data");
      }
    }
    eq->names.push_back(term_parameter_name(term));
    eq->cols.push_back(term_column(d, term));
    if (known_values) (*known_values)[term_parameter_name(term)] = term.coefficient;
  }
  return m;
}

/// The scan index of the effect `spec` with parameters `params` on `d`: the delay in samples of
/// a scanned delay (its scan parameter, at least one sample), the first sample at or after the
/// change time of a scanned change, 0 otherwise.
Index scan_index(const CandidateSpec& spec, const std::map<std::string, double>& params, const UniformData& d) {
  const auto it = params.find(spec.scan_parameter());
  if (it == params.end()) return 0;
  if (spec.scan == effects::Scan::kDelay) return std::max<Index>(1, std::lround(it->second * d.rate_hz));
  if (spec.scan == effects::Scan::kChangeTime) {
    const auto first = std::lower_bound(d.t_s.data(), d.t_s.data() + d.size(), it->second);
    return static_cast<Index>(first - d.t_s.data());
  }
  return 0;
}

/// t - t_mid of the drift's column: the time from the middle of the record [s].
VectorXd drift_time(const UniformData& d) {
  const Index n = d.size();
  return (d.t_s.array() - 0.5 * (d.t_s[0] + d.t_s[n - 1])).matrix();
}

/// The parameter of the input whose delay actuator_delay tests in equation `eq`: delta_f's
/// derivative in L and Y (L_df, Y_df), the command's gain in the actuator equation (F_cmd).

std::string delayed_input(const std::string& eq) { return eq == "F" ? "F_cmd" : eq + "_df"; }

std::string fmt(double x, int digits) {
  std::ostringstream o;
  o.precision(digits);
  o << x;
  return o.str();
}

}  // namespace nimble::ident::discrepancy_parts
