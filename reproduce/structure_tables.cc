/// The thesis's model-structure tables from the rig's flights (reproduce/structure_tables.h).

#include "reproduce/structure_tables.h"

#include <cmath>
#include <stdexcept>

namespace nimble::reproduce {
namespace {

constexpr double kDegPerRad = 180.0 / M_PI;
/// The low-pass cut-off of the thesis's four-state identifications (Figures 8.3, 8.5: order 10,
/// 12 Hz; the three-state ones lowered it to 9 Hz, Section 8.3.2).
constexpr double kFourStateCutoffHz = 12.0;

/// The parameters of `r`'s identified model (extra regressors left out): "<row> / <name>".
void put_derivatives(CellMap& m, const std::string& row, const ident::IdentResult& r) {
  for (const auto& [name, value] : r.model.derivatives) m[row + " / " + name] = value;
}

/// The thesis's own structure, with nothing of the rig's added: what Appendix H's correlations
/// are of.
ident::IdentResult identify_plain(const ident::FlightData& data, const Vehicle& vehicle, ident::IdentOptions options) {
  options.trim.w0_mps = data.at("w").values.front();
  return ident::identify(data, vehicle, vehicle.file, options);
}

void put_model_eigenvectors(CellMap& m, const DerivativeModel& model) {
  const Vehicle v = load_vehicle(model.vehicle_file);
  const StateSpace ss = build_state_space(model, v);
  put_eigenvectors(m, ss, analyse_modes(ss, v));
}

}  // namespace

ident::IdentResult identify_as_thesis(const ident::FlightData& data, const Vehicle& vehicle,
                                      const std::string& vehicle_file, const std::string& name,
                                      ident::IdentOptions options) {
  options.trim.w0_mps = data.at("w").values.front();
  options.model_name = name;
  if (!is_blackbox(options.structure)) {
    const double w0 = options.trim.w0_mps, g = vehicle.gravity_mps2;
    options.add_signals = [w0, g](ident::UniformData& d) {
      d.signals["pw"] = d.at("p").cwiseProduct((d.at("w").array() - w0).matrix());
      d.signals["gphi"] = (g * (d.at("phi").array().sin() - d.at("phi").array())).matrix();
    };
    options.extra_regressors = {{"Y", "pw"}, {"Y", "gphi"}};
  }
  return ident::identify(data, vehicle, vehicle_file, options);
}

void put_fit(CellMap& m, const std::string& row, const ident::FitMetrics& f) {
  m[row + " / rxy"] = f.rxy;
  m[row + " / R2"] = f.r2;
  m[row + " / RMSE %"] = f.rmse_pct_range;
}

const ident::OutputFit& fit_of(const std::vector<ident::OutputFit>& fits, const std::string& output) {
  for (const auto& f : fits) {
    if (f.output == output) return f;
  }
  throw std::runtime_error("no fit of " + output);
}

void put_eigenvalues(CellMap& m, const std::string& row, const std::vector<std::complex<double>>& eig) {
  double real = NAN;
  std::complex<double> osc(NAN, NAN);
  for (const auto& e : eig) {
    if (std::fabs(e.imag()) < 1e-9) {
      real = e.real();
    } else if (e.imag() > 0) {
      osc = e;
    }
  }
  m[row + " / aperiodic"] = real;
  m[row + " / oscillatory re"] = osc.real();
  m[row + " / oscillatory im"] = osc.imag();
}

void put_eigenvalues4(CellMap& m, const std::string& row, const std::vector<std::complex<double>>& eig) {
  for (const auto& e : eig) {
    if (std::fabs(e.imag()) > 1e-9) {
      if (e.imag() > 0) {
        m[row + " / oscillatory re"] = e.real();
        m[row + " / oscillatory im"] = e.imag();
      }
    } else {
      m[row + (e.real() < 0 ? " / aperiodic stable" : " / aperiodic unstable")] = e.real();
    }
  }
}

void put_eigenvectors(CellMap& m, const StateSpace& ss, const std::vector<Mode>& modes) {
  for (std::size_t k = 0; k < modes.size(); ++k) {
    const std::string mode = "mode " + std::to_string(k + 1);
    for (std::size_t i = 0; i < ss.states.size(); ++i) {
      if (ss.states[i] == "phi") continue;
      const std::complex<double> c = modes[k].eigenvector_nondim[static_cast<Eigen::Index>(i)];
      const std::string cell = ss.states[i] + "+ / " + mode;
      if (!modes[k].oscillatory) {
        m[cell] = c.real();  // a real mode's component: the thesis's phase 0 or 180 deg is its sign
        continue;
      }
      double phase = std::arg(c) * kDegPerRad;
      if (phase <= -180.0 + 1e-9) phase += 360.0;  // -180 is printed as 180
      m[cell] = std::abs(c);
      m[cell + " phase"] = phase;
    }
  }
}

void put_correlations(CellMap& m, const ident::IdentResult& r, const std::string& equation) {
  for (const auto& eq : r.regression.equations) {
    if (eq.equation.name != equation) continue;
    const auto& names = eq.equation.parameters;
    for (Eigen::Index i = 0; i < eq.correlation.rows(); ++i) {
      for (Eigen::Index k = i + 1; k < eq.correlation.cols(); ++k) {
        const std::string& a = names[static_cast<std::size_t>(i)];
        const std::string& b = names[static_cast<std::size_t>(k)];
        m[a + " / " + b] = m[b + " / " + a] = std::fabs(eq.correlation(i, k));
      }
    }
  }
}

std::map<std::string, CellMap> three_state_tables(const ident::FlightData& measured, const ident::IdentResult& set1) {
  std::map<std::string, CellMap> t;
  const Vehicle& vehicle = set1.vehicle;
  ident::IdentOptions o;
  o.inputs = set1.inputs;
  o.structure = Structure::kBlackbox3;
  const ident::IdentResult bb = identify_as_thesis(measured, vehicle, vehicle.file, "rig_blackbox3", o);
  for (const char* out : {"p_dot", "v_dot", "phi_dot"}) put_fit(t["8.7"], out, fit_of(bb.fits, out).metrics);
  put_eigenvectors(t["8.13"], set1.state_space, set1.modes);
  put_eigenvalues(t["8.14"], "set 1", bb.eigenvalues);
  put_eigenvectors(t["8.15"], bb.state_space, bb.modes);

  o.structure = Structure::kLateral3;
  o.method = ident::Method::kOls;
  put_derivatives(t["D.2"], "OLS", identify_as_thesis(measured, vehicle, vehicle.file, "rig_ols", o));
  put_derivatives(t["D.2"], "WLS", set1);

  o.method = ident::Method::kWls;
  const ident::IdentResult plain = identify_plain(measured, vehicle, o);
  put_correlations(t["H.4"], plain, "L");
  put_correlations(t["H.5"], plain, "Y");
  return t;
}

std::map<std::string, CellMap> four_state_tables(const ident::FlightData& measured, const DerivativeModel& plant) {
  std::map<std::string, CellMap> t;
  const Vehicle vehicle = load_vehicle(plant.vehicle_file);
  ident::IdentOptions o;
  o.structure = Structure::kLateral4;
  o.trim = plant.trim;  // the thesis's four-state trim (the plant file's, from its Eq D.1)
  o.processing.cutoff_hz = kFourStateCutoffHz;
  const ident::IdentResult grey = identify_as_thesis(measured, vehicle, vehicle.file, "rig_lateral4", o);
  put_fit(t["8.2"], "p_dot", fit_of(grey.fits, "p_dot").metrics);
  put_fit(t["8.2"], "r_dot", fit_of(grey.fits, "r_dot").metrics);
  put_fit(t["8.2"], "v_dot", fit_of(grey.fits, "v_dot_star").metrics);
  put_eigenvectors(t["8.9"], grey.state_space, grey.modes);
  put_derivatives(t["D.1"], "WLS", grey);

  o.inputs = grey.inputs;
  o.structure = Structure::kBlackbox4;
  const ident::IdentResult bb = identify_as_thesis(measured, vehicle, vehicle.file, "rig_blackbox4", o);
  for (const char* out : {"p_dot", "r_dot", "v_dot", "phi_dot"}) put_fit(t["8.4"], out, fit_of(bb.fits, out).metrics);
  put_eigenvalues4(t["8.10"], "lateral4", bb.eigenvalues);
  put_eigenvectors(t["8.11"], bb.state_space, bb.modes);

  o.structure = Structure::kLateral4;
  o.method = ident::Method::kOls;
  put_derivatives(t["D.1"], "OLS", identify_as_thesis(measured, vehicle, vehicle.file, "rig_lateral4_ols", o));

  o.method = ident::Method::kWls;
  const ident::IdentResult plain = identify_plain(measured, vehicle, o);
  put_correlations(t["H.1"], plain, "L");
  put_correlations(t["H.2"], plain, "N");
  put_correlations(t["H.3"], plain, "Y");
  return t;
}

const std::vector<std::string>& four_state_table_ids() {
  static const std::vector<std::string> ids = {"8.2", "8.4", "8.9", "8.10", "8.11", "D.1", "H.1", "H.2", "H.3"};
  return ids;
}

CellMap input_variant_table(const ident::FlightData& measured, const DerivativeModel& plant) {
  const Vehicle vehicle = load_vehicle(plant.vehicle_file);
  ident::IdentOptions o;
  o.inputs = plant.inputs;
  CellMap m;
  put_derivatives(m, "set 1", identify_as_thesis(measured, vehicle, vehicle.file, "rig_" + plant.name, o));
  return m;
}

std::map<std::string, CellMap> structure_model_tables(const CampaignSpec& spec) {
  std::map<std::string, CellMap> t;
  const DerivativeModel lateral4 = load_model(spec.lateral4_model);
  const DerivativeModel set1 = load_model(spec.sets.front().model);
  put_model_eigenvectors(t["8.9-model"], lateral4);
  put_model_eigenvectors(t["8.13-model"], set1);
  for (const char* row : {"OLS", "WLS"}) {
    for (const auto& [name, value] : lateral4.derivatives)
      t[kPlantDerivativesD1][std::string(row) + " / " + name] = value;
    for (const auto& [name, value] : set1.derivatives) t[kPlantDerivativesD2][std::string(row) + " / " + name] = value;
  }
  for (const auto& [id, file] : spec.input_variants) {
    for (const auto& [name, value] : load_model(file).derivatives) t[id + "-model"]["set 1 / " + name] = value;
  }
  return t;
}

}  // namespace nimble::reproduce
