#include "ident/validate.h"

#include "ident/data_check.h"

namespace nimble::ident {

ValidationResult validate_open_loop(const FlightData& data, const DerivativeModel& model, const Vehicle& vehicle,
                                    const ValidationOptions& options) {
  check_flight_data(data, vehicle);
  check_excitation(data, state_names(model.structure), model.inputs);
  ValidationResult res;
  res.source = data.source;
  res.model = model;
  res.vehicle = vehicle;
  res.state_space = build_state_space(model, vehicle);
  const StateSpace& ss = res.state_space;

  std::vector<std::string> missing;
  for (const auto* list : {&ss.states, &ss.inputs}) {
    for (const auto& name : *list) {
      if (!data.has(name)) missing.push_back(name);
    }
  }
  if (!missing.empty()) {
    std::string names;
    for (const auto& m : missing) names += (names.empty() ? "" : ", ") + m;
    throw DataError(data.source, -1, -1, missing.front(),
                    "model " + model.name + " needs column" + (missing.size() > 1 ? "s " : " ") + names);
  }

  res.data = process(data, options.processing);
  UniformData& d = res.data;
  const Eigen::Index n = d.size();
  const Eigen::Index nx = static_cast<Eigen::Index>(ss.states.size());
  const Eigen::Index nu = static_cast<Eigen::Index>(ss.inputs.size());
  Eigen::MatrixXd X(nx, n), U(nu, n);
  for (Eigen::Index i = 0; i < nx; ++i) X.row(i) = d.at(ss.states[static_cast<std::size_t>(i)]).transpose();
  for (Eigen::Index j = 0; j < nu; ++j) U.row(j) = d.at(ss.inputs[static_cast<std::size_t>(j)]).transpose();
  Eigen::MatrixXd predicted = ss.A * X + ss.B * U;
  // The model's generic terms: coefficient * expression along the record, through the inertia or mass.
  for (const auto& term : model.terms) {
    for (const auto& s : term.expression.signals()) {
      if (!d.signals.count(s)) {
        throw DataError(data.source, -1, -1, s,
                        "model " + model.name + " needs column " + s + " for its term " + term_parameter_name(term));
      }
    }
    add_term_column(d, term);
    predicted +=
        term.coefficient * term_state_gain(model, vehicle, term.equation) * d.at(term_signal_column(term)).transpose();
  }

  const std::size_t lag_step = whiteness_lag_step(options.whiteness_lag_step, options.processing);
  for (Eigen::Index i = 0; i < nx; ++i) {
    const std::string& s = ss.states[static_cast<std::size_t>(i)];
    d.signals[s + "_dot"] = differentiate(d.at(s), d.rate_hz);
    OutputFit fit;
    fit.output = s + "_dot";
    fit.unit = ss.state_units[static_cast<std::size_t>(i)] + "/s";
    if (fit.unit == "rad/s/s") fit.unit = "rad/s^2";
    if (fit.unit == "m/s/s") fit.unit = "m/s^2";
    fit.measured = d.at(fit.output);
    fit.estimated = predicted.row(i).transpose();
    fit.metrics = fit_metrics(fit.measured, fit.estimated, 1);
    fit.whiteness = residual_whiteness(fit.measured - fit.estimated, d.rate_hz, options.whiteness_lags, lag_step);
    res.fits.push_back(std::move(fit));
  }
  if (!res.fits.empty() && !res.fits.front().whiteness.tested) res.notes.push_back(res.fits.front().whiteness.note);
  return res;
}

}  // namespace nimble::ident
