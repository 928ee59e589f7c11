#include "ident/closed_loop.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "ident/plots.h"
#include "ident/signal.h"

namespace nimble::ident {

ClosedLoopResult validate_closed_loop(const FlightData& data, const DerivativeModel& model, const Vehicle& vehicle,
                                      const ClosedLoopOptions& options) {
  if (model.structure != Structure::kLateral3) {
    throw std::invalid_argument("closed-loop validation needs a lateral3 model; '" + model.name + "' is " +
                                to_string(model.structure));
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

  const double rate_hz = options.controller.rate_hz;
  const UniformData grid = resample_uniform(data, rate_hz, options.interpolation);
  const Eigen::Index n = grid.size();

  // Plant x = [p v phi delta_f], inputs [delta_f_cmd, delta_t]: the model with the flap
  // actuator of Eq 33 in front of it, exact ZOH at the controller's rate.
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
  const DiscreteStateSpace d = discretize_zoh(plant, 1.0 / rate_hz);

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
  r.gain_set = options.gain_set;
  r.rate_hz = rate_hz;
  r.t_s = grid.t_s;
  r.measured = {{"p", p}, {"v", v}, {"phi", phi}, {"delta_f", df}};
  for (const auto& [name, m] : r.measured) r.simulated[name] = Eigen::VectorXd::Zero(n);

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
    const Eigen::Vector2d u(out.delta_f_cmd_radps, dt[k]);
    x = d.Ad * x + d.Bd * u;
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
  std::vector<TimePanel> panels;
  for (const Signal& s : signals) {
    const FitMetrics& f = r.fits.at(s.name);
    char title[200];
    std::snprintf(title, sizeof title, "%s   r_xy %.3f  R^2 %.3f  RMSE %.3g %s (%.1f %% of range)", s.name, f.rxy, f.r2,
                  f.rmse, s.unit, f.rmse_pct_range);
    TimePanel panel;
    panel.name = s.name;
    panel.title = title;
    panel.ylabel = std::string(s.name) + " [" + s.unit + "]";
    panel.series.push_back({"measured", r.measured.at(s.name), "#1f77b4", false});
    panel.series.push_back({"simulated", r.simulated.at(s.name), "#d62728", false});
    if (std::string(s.name) == "phi") panel.series.push_back({"phi_sp", r.phi_sp, "#2ca02c", true});
    panels.push_back(std::move(panel));
  }
  const std::string title = "closed-loop validation: " + r.model + " flown by the controller copy (gains " + r.gain_set +
                            ") on phi_sp of " + r.source;
  return {plot_time_histories(dir, "closed_loop", title, r.t_s, panels)};
}

}  // namespace nimble::ident
