#include "ident/closed_loop.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "core/json_line.h"
#include "ident/data_check.h"
#include "ident/plots.h"
#include "ident/signal.h"
#include "plots/gnuplot.h"

namespace nimble::ident {
namespace {

/// The effects of `model` (section effects:, as rig discrepancy writes them) as extra roll
/// moment and side force at one step of the closed-loop simulation, from the simulated p, v,
/// phi, delta_f (and delta_f's history for a delay) and the measured exogenous channels the
/// model does not simulate (u, w, delta_d, r), at time t.
class EffectForces {
 public:
  EffectForces(const DerivativeModel& model, const Vehicle& vehicle, const UniformData& grid)
      : model_(model), g_(vehicle.gravity_mps2), grid_(grid) {
    for (const auto& [name, params] : model.effects) {
      for (const auto& [key, value] : params) {
        if (key == "delay_s") delay_samples_ = std::max<Eigen::Index>(1, std::lround(value * grid.rate_hz));
        if (key == "flapping_hz") flapping_hz_ = value;
        if (key == "t_mid_s") t_mid_s_ = value;
        if (key == "t_change_s") t_change_s_ = value;
      }
    }
    for (const auto& [name, params] : model.effects) {
      for (const char* need : {"u", "w", "delta_d", "r"}) {
        bool used = false;
        for (const auto& [key, value] : params) used = used || uses(key, need);
        if (used && !grid.has(need)) {
          throw DataError(grid.source, -1, -1, need, "the model's effect " + name + " needs this channel");
        }
      }
    }
  }

  /// Samples by which the flap command reaches the actuator late: an actuator_delay named in
  /// the actuator equation (F_cmd_delayed), 0 otherwise.
  Eigen::Index command_delay_samples() const {
    for (const auto& [name, params] : model_.effects) {
      if (params.count("F_cmd_delayed")) return delay_samples_;
    }
    return 0;
  }

  /// Extra L [N m] and Y [N] at sample k.
  std::pair<double, double> at(Eigen::Index k, double p, double v, double phi,
                               const std::vector<double>& df_hist) const {
    double L = 0.0, Y = 0.0;
    const Trim& trim = model_.trim;
    const double t = grid_.t_s[k] - grid_.t_s[0];
    for (const auto& [name, params] : model_.effects) {
      for (const auto& [key, c] : params) {
        if (key == "delay_s" || key == "flapping_hz" || key.find("_amp") != std::string::npos ||
            key.find("fraction") != std::string::npos || key.rfind("F_", 0) == 0 || key.rfind("rate_per_min", 0) == 0 ||
            key.rfind("t_", 0) == 0) {
          continue;  // not a force (F_: the actuator's command delay, command_delay_samples())
        }
        double x = 0.0;
        const std::string form = key.substr(key.find('_') == 1 ? 2 : 1);  // "L_vv" -> "vv", "Lr" -> "r"
        if (form == "pw")
          x = p * (grid_.at("w")[k] - trim.w0_mps);
        else if (form == "gphi")
          x = g_ * std::cos(trim.theta0_rad) * (std::sin(phi) - phi);
        else if (form == "vv")
          x = v * std::fabs(v);
        else if (form == "up")
          x = (grid_.at("u")[k] - trim.u0_mps) * p;
        else if (form == "uv")
          x = (grid_.at("u")[k] - trim.u0_mps) * v;
        else if (form == "df_delayed") {
          const std::size_t n = df_hist.size();
          const std::size_t back = static_cast<std::size_t>(delay_samples_);
          x = df_hist[n > back ? n - 1 - back : 0] - df_hist.back();
        } else if (form == "df_rate")
          x = (grid_.t_s[k] - t_mid_s_) * df_hist.back();
        else if (form == "df_step")
          x = grid_.t_s[k] >= t_change_s_ ? df_hist.back() : 0.0;
        else if (form == "0")
          x = 1.0;
        else if (form == "dd")
          x = grid_.at("delta_d")[k];
        else if (form == "r")
          x = grid_.at("r")[k];
        else if (form.rfind("sin", 0) == 0)
          x = std::sin(2.0 * M_PI * std::stoi(form.substr(3)) * flapping_hz_ * t);
        else if (form.rfind("cos", 0) == 0)
          x = std::cos(2.0 * M_PI * std::stoi(form.substr(3)) * flapping_hz_ * t);
        else
          throw std::invalid_argument("closed loop: effect parameter '" + key + "' of " + name + " has no form");
        (key[0] == 'L' ? L : Y) += c * x;
      }
    }
    return {L, Y};
  }

 private:
  static bool uses(const std::string& key, const char* channel) {
    const std::string c = channel;
    if (c == "u") return key.size() > 3 && (key.substr(key.size() - 2) == "up" || key.substr(key.size() - 2) == "uv");
    if (c == "w") return key.size() >= 4 && key.substr(key.size() - 2) == "pw";
    if (c == "delta_d") return key.size() >= 4 && key.substr(key.size() - 2) == "dd";
    return key == "Lr" || key == "Yr";
  }
  const DerivativeModel& model_;
  double g_;
  const UniformData& grid_;
  Eigen::Index delay_samples_ = 1;
  double flapping_hz_ = 0.0;
  double t_mid_s_ = 0.0;     ///< effectiveness_drift: the time its L_df, Y_df hold [s]
  double t_change_s_ = 0.0;  ///< effectiveness_step: the change [s]
};

/// Checks the model and the data for a closed-loop validation; returns the columns of delta_f and
/// delta_t among the model's inputs (-1: not an input).
std::pair<int, int> input_columns(const FlightData& data, const DerivativeModel& model, const Vehicle& vehicle) {
  check_flight_data(data, vehicle);
  check_excitation(data, state_names(model.structure), model.inputs);
  // The simulation takes the model's A and B whole (its own phi-dot row for a black box).
  if (model.structure != Structure::kLateral3 && model.structure != Structure::kBlackbox3) {
    throw std::invalid_argument("closed-loop validation needs a three-state model (lateral3 or blackbox3); '" +
                                model.name + "' is " + to_string(model.structure));
  }
  int i_df = -1, i_dt = -1;
  for (std::size_t j = 0; j < model.inputs.size(); ++j) {
    if (model.inputs[j] == "delta_f") i_df = static_cast<int>(j);
    if (model.inputs[j] == "delta_t") i_dt = static_cast<int>(j);
  }
  if (i_df < 0) throw std::invalid_argument("closed-loop validation needs a model with the input delta_f");
  for (const char* name : {"p", "v", "phi", "delta_f", "phi_sp"}) {
    if (!data.has(name)) {
      throw DataError(data.source, -1, -1, name, "closed-loop validation needs this channel");
    }
  }
  if (i_dt >= 0 && !data.has("delta_t")) {
    throw DataError(data.source, -1, -1, "delta_t", "the model has delta_t; the data must too");
  }
  return {i_df, i_dt};
}

/// Plant x = [p v phi delta_f], inputs [delta_f_cmd, delta_t]: the model with the flap
/// actuator of Eq 33 in front of it, exact ZOH at the controller's rate.
DiscreteStateSpace closed_loop_plant(const DerivativeModel& model, const Vehicle& vehicle, int i_df, int i_dt,
                                     const ClosedLoopOptions& options) {
  const double rate_hz = options.controller.rate_hz;
  const StateSpace lateral = build_state_space(model, vehicle);
  StateSpace plant;
  plant.states = {"p", "v", "phi", "delta_f"};
  plant.state_units = {"rad/s", "m/s", "rad", "rad/s"};
  plant.inputs = {"delta_f_cmd", "delta_t"};
  plant.input_units = {"rad/s", "%"};
  plant.A = Eigen::MatrixXd::Zero(4, 4);
  plant.B = Eigen::MatrixXd::Zero(4, 2);
  plant.A.topLeftCorner(3, 3) = lateral.A;
  plant.A.block(0, 3, 3, 1) = lateral.B.col(i_df);
  plant.A(3, 3) = -options.flap_pole_radps;
  plant.B(3, 0) = options.flap_gain_per_s;
  if (i_dt >= 0) plant.B.block(0, 1, 3, 1) = lateral.B.col(i_dt);
  return discretize_zoh(plant, 1.0 / rate_hz);
}

/// The model's generic terms, compiled; `from_data` gets the data's column of each signal a term
/// reads that is not simulated.
std::vector<TermProgram> compile_terms(const FlightData& data, const DerivativeModel& model, const UniformData& grid,
                                       int i_dt, std::vector<const Eigen::VectorXd*>& from_data) {
  const std::vector<std::string>& term_names = term_signal_names();
  std::vector<TermProgram> terms;
  for (const auto& term : model.terms) {
    terms.emplace_back(term.expression, term_names);
    for (const auto& s : term.expression.signals()) {
      const auto i = static_cast<std::size_t>(std::find(term_names.begin(), term_names.end(), s) - term_names.begin());
      if (s == "p" || s == "v" || s == "phi" || s == "delta_f" || (s == "delta_t" && i_dt >= 0)) continue;
      if (!grid.has(s)) {
        throw DataError(data.source, -1, -1, s,
                        "the model's term " + term_parameter_name(term) + " needs " + s + ", not in the data");
      }
      from_data[i] = &grid.at(s);
    }
  }
  return terms;
}

}  // namespace

ClosedLoopResult validate_closed_loop(const FlightData& data, const DerivativeModel& model, const Vehicle& vehicle,
                                      const ClosedLoopOptions& options) {
  const auto [i_df, i_dt] = input_columns(data, model, vehicle);

  const double rate_hz = options.controller.rate_hz;
  const UniformData grid = resample_uniform(data, rate_hz, options.interpolation);
  const Eigen::Index n = grid.size();

  const DiscreteStateSpace d = closed_loop_plant(model, vehicle, i_df, i_dt, options);

  AttitudeController controller(options.controller);
  if (!controller.select_gain_set(options.gain_set)) {
    throw std::invalid_argument("unknown roll gain set '" + options.gain_set + "'");
  }
  const Eigen::VectorXd& p = grid.at("p");
  const Eigen::VectorXd& v = grid.at("v");
  const Eigen::VectorXd& phi = grid.at("phi");
  const Eigen::VectorXd& df = grid.at("delta_f");
  const Eigen::VectorXd& phi_sp = grid.at("phi_sp");
  const Eigen::VectorXd dt = i_dt >= 0 ? grid.at("delta_t") : Eigen::VectorXd::Zero(n);
  controller.reset(phi[0]);
  controller.select_gain_set(options.gain_set);

  ClosedLoopResult r;
  r.source = data.source;
  r.model = model.name;
  r.phi_sp = phi_sp;
  r.phi_ref = Eigen::VectorXd::Zero(n);
  r.gain_set = options.gain_set;
  r.rate_hz = rate_hz;
  r.t_s = grid.t_s;
  r.measured = {{"p", p}, {"v", v}, {"phi", phi}, {"delta_f", df}};
  for (const auto& [name, m] : r.measured) r.simulated[name] = Eigen::VectorXd::Zero(n);

  // Effects beyond the linear model enter as extra moment and force, held over each step
  // (forward Euler on their contribution; the linear part stays exact).
  const EffectForces effects(model, vehicle, grid);
  const double Izz_over_Ic = vehicle.Izz_kgm2 / vehicle.Ic();
  std::vector<double> df_hist, cmd_hist;
  const Eigen::Index cmd_delay = effects.command_delay_samples();
  // The model's generic terms: flown with the simulated p, v, phi, delta_f and the data's
  // delta_t; any other signal a term reads (r, u, w, ...) is taken from the data.
  const std::vector<std::string>& term_names = term_signal_names();
  std::vector<const Eigen::VectorXd*> from_data(term_names.size(), nullptr);
  std::vector<TermProgram> terms = compile_terms(data, model, grid, i_dt, from_data);
  std::vector<double> term_in(term_names.size(), 0.0);
  Eigen::Vector4d x(p[0], v[0], phi[0], df[0]);
  for (Eigen::Index k = 0; k < n; ++k) {
    r.simulated["p"][k] = x[0];
    r.simulated["v"][k] = x[1];
    r.simulated["phi"][k] = x[2];
    r.simulated["delta_f"][k] = x[3];
    ControllerInput in;
    in.phi_rad = x[2];
    in.p_radps = x[0];
    in.roll_sp_rad = phi_sp[k];
    const ControllerOutput out = controller.step(in);
    r.phi_ref[k] = out.roll_ref_rad;
    cmd_hist.push_back(out.delta_f_cmd_radps);
    const Eigen::Index back = static_cast<Eigen::Index>(cmd_hist.size()) - 1 - cmd_delay;
    const Eigen::Vector2d u(back >= 0 ? cmd_hist[static_cast<std::size_t>(back)] : 0.0, dt[k]);
    df_hist.push_back(x[3]);
    auto [dL, dY] =
        model.effects.empty() ? std::pair<double, double>{0.0, 0.0} : effects.at(k, x[0], x[1], x[2], df_hist);
    if (!terms.empty()) {
      for (std::size_t i = 0; i < term_names.size(); ++i) term_in[i] = from_data[i] ? (*from_data[i])[k] : 0.0;
      term_in[0] = x[0];  // term_signal_names(): p q r u v w phi theta delta_f delta_t delta_d delta_w
      term_in[4] = x[1];
      term_in[6] = x[2];
      term_in[8] = x[3];
      term_in[9] = dt[k];
      for (std::size_t i = 0; i < terms.size(); ++i) {
        const double load = model.terms[i].coefficient * terms[i].evaluate(term_in.data());
        (model.terms[i].equation == "L" ? dL : dY) += load;
        terms[i].advance(1.0 / rate_hz);
      }
    }
    x = d.Ad * x + d.Bd * u;
    x[0] += Izz_over_Ic * dL / rate_hz;
    x[1] += dY / vehicle.mass_kg / rate_hz;
  }
  for (const auto& [name, m] : r.measured) r.fits[name] = fit_metrics(m, r.simulated[name], 1);
  return r;
}

std::vector<std::string> plot_closed_loop(const ClosedLoopResult& r, const std::string& dir) {
  struct Signal {
    const char* name;
    const char* unit;
  };
  const Signal signals[] = {{"p", "rad/s"}, {"phi", "rad"}, {"v", "m/s"}, {"delta_f", "rad/s"}};
  std::vector<plots::TimePanel> panels;
  for (const Signal& s : signals) {
    const FitMetrics& f = r.fits.at(s.name);
    char title[200];
    std::snprintf(title, sizeof title, "%s   r_xy %.3f  R^2 %.3f  RMSE %.3g %s (%.1f %% of range)", s.name, f.rxy, f.r2,
                  f.rmse, s.unit, f.rmse_pct_range);
    plots::TimePanel panel;
    panel.name = s.name;
    panel.title = title;
    panel.ylabel = std::string(s.name) + " [" + s.unit + "]";
    panel.series.push_back({"measured", r.measured.at(s.name), "#1f77b4", false});
    panel.series.push_back({"simulated", r.simulated.at(s.name), "#d62728", false});
    if (std::string(s.name) == "phi") {
      panel.series.push_back({"phi_sp", r.phi_sp, "#2ca02c", true});
      panel.series.push_back({"phi_ref", r.phi_ref, "#9467bd", true});  // the controller copy's
    }
    panels.push_back(std::move(panel));
  }
  const std::string title = "closed-loop validation: " + r.model + " flown by the controller copy (gains " +
                            r.gain_set + ") on phi_sp of " + r.source;
  // Residual autocorrelation of each simulated signal (thesis Figs C.4-C.9), lags as for the
  // identification's 9 Hz data.
  std::vector<OutputFit> fits;
  ProcessingOptions processing;
  processing.rate_hz = r.rate_hz;
  const std::size_t lag_step = whiteness_lag_step(0, processing);
  for (const Signal& s : signals) {
    OutputFit f;
    f.output = s.name;
    f.unit = s.unit;
    f.measured = r.measured.at(s.name);
    f.estimated = r.simulated.at(s.name);
    f.metrics = r.fits.at(s.name);
    f.whiteness = residual_whiteness(f.measured - f.estimated, r.rate_hz, 50, lag_step);
    fits.push_back(std::move(f));
  }
  return {plots::plot_time_histories(dir, "closed_loop", title, r.t_s, panels),
          plot_autocorrelation(dir, fits, "residual autocorrelation, closed loop: " + r.model + " on " + r.source)};
}

std::string closed_loop_json(const ClosedLoopResult& r, const std::vector<std::string>& plots) {
  OrderedJson j;
  j["source"] = r.source;
  j["model"] = r.model;
  j["gain_set"] = r.gain_set;
  j["rate_hz"] = r.rate_hz;
  j["samples"] = r.t_s.size();
  OrderedJson& fits = j["closed_loop"] = OrderedJson::object();
  for (const char* name : {"p", "v", "phi", "delta_f"}) {
    const FitMetrics& f = r.fits.at(name);
    fits[name] = {
        {"rxy", f.rxy}, {"r2", f.r2}, {"rmse", f.rmse}, {"range", f.range}, {"rmse_pct_range", f.rmse_pct_range}};
  }
  if (!plots.empty()) j["plots"] = plots;
  return json_line(j);
}

std::string default_controller_file() { return NIMBLE_DEFAULT_CONTROLLER; }

}  // namespace nimble::ident
