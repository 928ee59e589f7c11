// The identification's and the validation's JSON reports (ident/report.h; `rig identify --json`,
// `rig validate --json`): each part with its function over nlohmann::ordered_json (keys in the
// order written, numbers as the shortest text that reads back to the same double, a non-finite
// number as null). The keys and their order are the reports' format (docs/identification.md).

#include <cmath>
#include <complex>

#include "ident/report.h"
#include "ident/report_numbers.h"
#include "core/json_line.h"

namespace nimble::ident {
namespace {

/// Each output's fit metrics, its whiteness fraction (null: not tested) and the test's detail, into `j`.
void add_fits(OrderedJson& j, const std::vector<OutputFit>& fits) {
  j["metrics"] = OrderedJson::object();
  for (const auto& f : fits) {
    j["metrics"][f.output] = {{"rxy", f.metrics.rxy},
                              {"r2", f.metrics.r2},
                              {"rmse", f.metrics.rmse},
                              {"range", f.metrics.range},
                              {"rmse_pct_range", f.metrics.rmse_pct_range},
                              {"unit", f.unit},
                              {"samples", f.metrics.samples},
                              {"parameters", f.metrics.parameters}};
  }
  // A whiteness test skipped on a short record: null fractions, and the note saying what it needs.
  j["whiteness"] = OrderedJson::object();
  for (const auto& f : fits) {
    j["whiteness"][f.output] = f.whiteness.tested ? OrderedJson(f.whiteness.fraction_outside) : OrderedJson(nullptr);
  }
  j["whiteness_detail"] = OrderedJson::object();
  for (const auto& f : fits) {
    const Whiteness& x = f.whiteness;
    OrderedJson& d = j["whiteness_detail"][f.output];
    d = {{"tested", x.tested}};
    if (!x.tested) {
      d["note"] = x.note;
      d["lags"] = x.lags;
      d["lag_step_samples"] = x.lag_step;
      continue;
    }
    d["white"] = x.white;
    d["fraction_outside"] = x.fraction_outside;
    d["allowed_fraction"] = x.allowed_fraction;
    d["outside"] = x.outside;
    d["lags"] = x.lags;
    d["lag_step_samples"] = x.lag_step;
    d["lag_step_s"] = x.lag_step_s;
    d["bound"] = x.bound;
    d["autocorrelation"] = std::vector<double>(x.rho.data(), x.rho.data() + x.rho.size());
  }
}

OrderedJson ranges_json(const std::vector<TimeRange>& ranges) {
  OrderedJson a = OrderedJson::array();
  for (const auto& r : ranges) a.push_back({r.start_s, r.end_s});
  return a;
}

/// Each parameter with its sigmas, each equation's correlation matrix, and the pairs over the threshold.
void add_parameters(OrderedJson& j, const IdentResult& r) {
  j["parameters"] = OrderedJson::object();
  for (const auto& name : r.parameter_order) {
    const ParameterEstimate& e = r.parameters.at(name);
    j["parameters"][name] = {{"value", e.value},
                             {"sigma", e.sigma},
                             {"sigma_pct", pct(e.sigma, e.value)},
                             {"sigma_coloured", e.sigma_coloured},
                             {"sigma_coloured_pct", pct(e.sigma_coloured, e.value)}};
  }
  j["correlation"] = OrderedJson::object();
  for (const auto& eq : r.regression.equations) {
    OrderedJson matrix = OrderedJson::array();
    for (Eigen::Index i = 0; i < eq.correlation.rows(); ++i) {
      OrderedJson row = OrderedJson::array();
      for (Eigen::Index k = 0; k < eq.correlation.cols(); ++k) row.push_back(eq.correlation(i, k));
      matrix.push_back(std::move(row));
    }
    j["correlation"][eq.equation.name] = {{"parameters", eq.equation.parameters}, {"matrix", std::move(matrix)}};
  }
  j["correlation_threshold"] = r.options.correlation_threshold;
  j["correlated_pairs"] = OrderedJson::array();
  for (const auto& c : r.correlated) {
    j["correlated_pairs"].push_back({{"equation", c.equation}, {"a", c.a}, {"b", c.b}, {"rho", c.rho}});
  }
}

/// The identified model's eigenvalues and modes, each mode's eigenvector by state.
void add_modes(OrderedJson& j, const IdentResult& r) {
  j["eigenvalues"] = OrderedJson::array();
  for (const auto& z : r.eigenvalues) j["eigenvalues"].push_back({z.real(), z.imag()});
  j["modes"] = OrderedJson::array();
  for (const auto& m : r.modes) {
    OrderedJson vector = OrderedJson::object();
    for (std::size_t i = 0; i < r.state_space.states.size(); ++i) {
      const auto c = m.eigenvector_nondim[static_cast<Eigen::Index>(i)];
      vector[r.state_space.states[i]] = {{"magnitude", std::abs(c)}, {"phase_deg", phase_deg(c)}};
    }
    j["modes"].push_back({{"eigenvalue", {m.eigenvalue.real(), m.eigenvalue.imag()}},
                          {"oscillatory", m.oscillatory},
                          {"stable", m.stable},
                          {"natural_frequency_radps", m.natural_frequency_radps},
                          {"damping_ratio", m.damping_ratio},
                          {"eigenvector_nondim", std::move(vector)}});
  }
}

/// The hover and manoeuvre segments, and each state's PSD in each.
void add_segments(OrderedJson& j, const IdentResult& r) {
  j["segments"] = {{"how", r.segments.how},
                   {"hover", ranges_json(r.segments.hover)},
                   {"manoeuvre", ranges_json(r.segments.manoeuvre)}};
  j["psd"] = OrderedJson::object();
  for (const auto& p : r.psd) {
    OrderedJson& s = j["psd"][p.state];
    s = {{"unit", "(" + p.unit + ")^2/Hz"}};
    for (const auto* part : {&p.hover, &p.manoeuvre}) {
      const bool have = part == &p.hover ? p.has_hover : p.has_manoeuvre;
      const char* key = part == &p.hover ? "hover" : "manoeuvre";
      if (!have) {
        s[key] = nullptr;
        continue;
      }
      s[key] = {{"variance", part->integral()},
                {"variance_below_cutoff", part->integral_up_to(r.options.processing.cutoff_hz)},
                {"df_hz", part->df_hz},
                {"segments", part->segments}};
    }
  }
}

}  // namespace

std::string identification_json(const IdentResult& r, const std::string& model_out,
                                const std::vector<std::string>& plots) {
  const IdentOptions& o = r.options;
  OrderedJson j = {{"source", r.source}, {"structure", to_string(o.structure)},  {"method", to_string(o.method)},
                   {"inputs", r.inputs}, {"inputs_left_out", r.inputs_left_out}, {"notes", r.notes}};
  j["vehicle"] = {{"name", r.vehicle.name}, {"file", r.vehicle.file}, {"mass_kg", r.vehicle.mass_kg}};
  j["trim"] = {{"u0_mps", r.model.trim.u0_mps},
               {"w0_mps", r.model.trim.w0_mps},
               {"theta0_rad", r.model.trim.theta0_rad},
               {"phi0_rad", r.model.trim.phi0_rad}};
  j["processing"] = {{"rate_hz", o.processing.rate_hz},
                     {"interpolation", to_string(o.processing.interpolation)},
                     {"filter_order", o.processing.filter_order},
                     {"cutoff_hz", o.processing.cutoff_hz},
                     {"samples", r.data.filtered.size()}};
  if (o.method == Method::kWls) {
    j["wls"] = {{"window_s", o.wls_window_s},
                {"cross_equation", o.wls_cross_equation},
                {"scale_factor", r.regression.scale_factor}};
  }
  add_parameters(j, r);
  add_fits(j, r.fits);
  add_modes(j, r);
  add_segments(j, r);
  if (!model_out.empty()) j["model_out"] = model_out;
  if (!plots.empty()) j["plots"] = plots;
  return json_line(j);
}

std::string methods_comparison_json(const IdentResult& ols, const IdentResult& wls) {
  require_comparable(ols, wls);
  OrderedJson rows = OrderedJson::array();
  for (const auto& name : ols.parameter_order) {
    const auto one = [](const ParameterEstimate& e) {
      return OrderedJson{
          {"value", e.value}, {"sigma", std::fabs(e.sigma)}, {"rel_sigma_pct", pct(std::fabs(e.sigma), e.value)}};
    };
    rows.push_back({{"name", name}, {"ols", one(ols.parameters.at(name))}, {"wls", one(wls.parameters.at(name))}});
  }
  return json_line(rows);
}

std::string validation_json(const ValidationResult& r, const std::vector<std::string>& plots) {
  OrderedJson j = {{"source", r.source},         {"model", r.model.name},
                   {"model_file", r.model.file}, {"structure", to_string(r.model.structure)},
                   {"vehicle", r.vehicle.name},  {"samples", r.data.size()},
                   {"rate_hz", r.data.rate_hz},  {"notes", r.notes}};
  add_fits(j, r.fits);
  if (!plots.empty()) j["plots"] = plots;
  return json_line(j);
}

}  // namespace nimble::ident
