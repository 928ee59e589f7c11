#include "controller/linear_closed_loop.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace nimble {
namespace {

void extend(SignalRange& r, double x, bool first) {
  if (first) {
    r.min = r.max = x;
  } else {
    r.min = std::min(r.min, x);
    r.max = std::max(r.max, x);
  }
}

int input_index(const DerivativeModel& model, const std::string& name) {
  for (std::size_t i = 0; i < model.inputs.size(); ++i) {
    if (model.inputs[i] == name) return static_cast<int>(i);
  }
  return -1;
}

/// Beyond this the linear model has left any meaning: count the run as diverged.
constexpr double kDivergedState = 1e6;

}  // namespace

double range_score(const LinearLoopResult& r, const TargetRanges& t) {
  if (!r.finite) return INFINITY;
  const double ratios[4] = {r.p_radps.range() / t.p_radps, r.v_mps.range() / t.v_mps, r.phi_rad.range() / t.phi_rad,
                            r.delta_f_radps.range() / t.delta_f_radps};
  double sum = 0.0;
  for (const double x : ratios) {
    if (!(x > 0.0) || !std::isfinite(x)) return INFINITY;
    sum += std::log(x) * std::log(x);
  }
  return std::sqrt(sum / 4.0);
}

bool returned_to_hover(const LinearLoopResult& r, double phi_tol_rad, double p_tol_radps, double v_tol_mps) {
  return r.finite && r.settle_max_abs_phi_rad < phi_tol_rad && r.settle_max_abs_p_radps < p_tol_radps &&
         r.settle_max_abs_v_mps < v_tol_mps;
}

LinearLoopResult simulate_linear_closed_loop(const DerivativeModel& model, const Vehicle& vehicle,
                                             const ControllerConfig& controller_config, const std::string& gain_set,
                                             const ManoeuvrePlayer& player, const LinearLoopOptions& options) {
  if (model.structure != Structure::kLateral3) {
    throw std::invalid_argument("linear closed loop: model '" + model.name + "' must be lateral3, is " +
                                to_string(model.structure));
  }
  const int i_df = input_index(model, "delta_f");
  const int i_dt = input_index(model, "delta_t");
  if (i_df < 0) throw std::invalid_argument("linear closed loop: model '" + model.name + "' has no delta_f input");
  for (const std::string& input : model.inputs) {
    if (input != "delta_f" && input != "delta_t") {
      throw std::invalid_argument("linear closed loop: model '" + model.name + "' input '" + input +
                                  "' is not driven by the roll loop (only delta_f, delta_t)");
    }
  }
  if (!(options.plant_rate_hz > 0.0 && options.flap_pole_radps > 0.0 && options.tail_s >= 0.0 &&
        options.settle_window_s > 0.0)) {
    throw std::invalid_argument("linear closed loop: rates, pole and windows must be positive");
  }

  const StateSpace ss = build_state_space(model, vehicle);
  const double dt_p = 1.0 / options.plant_rate_hz;
  const DiscreteStateSpace d = discretize_zoh(ss, dt_p);
  const double a_flap = std::exp(-options.flap_pole_radps * dt_p);
  const double b_flap = options.flap_gain_per_s / options.flap_pole_radps * (1.0 - a_flap);

  AttitudeController controller(controller_config);
  if (!controller.select_gain_set(gain_set)) {
    roll_gain_set(controller_config, gain_set);  // throws, naming the set
  }
  const double dt_c = controller.dt_s();

  LinearLoopResult result;
  result.duration_s = player.duration_s() + options.tail_s;
  const long long n_steps = static_cast<long long>(std::ceil(result.duration_s * options.plant_rate_hz - 1e-9));
  const double settle_start = result.duration_s - options.settle_window_s;

  Eigen::VectorXd x = Eigen::VectorXd::Zero(3);  // [p v phi]
  Eigen::VectorXd u = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(model.inputs.size()));
  double delta_f = 0.0;
  ControllerOutput cmd;
  Setpoint sp;
  long long next_control = 0;

  for (long long k = 0; k <= n_steps; ++k) {
    const double t = static_cast<double>(k) * dt_p;
    // Every controller step due at or before t samples the current state.
    while (static_cast<double>(next_control) * dt_c <= t + 1e-12) {
      sp = player.at(static_cast<double>(next_control) * dt_c);
      ControllerInput in;
      in.p_radps = x(0);
      in.phi_rad = x(2);
      in.roll_sp_rad = sp.roll_sp_rad;
      in.pitch_sp_rad = sp.pitch_sp_rad;
      in.throttle_pct = sp.throttle_pct;
      in.throttle_factor = sp.throttle_factor;
      cmd = controller.step(in);
      ++next_control;
    }

    const bool first = k == 0;
    extend(result.p_radps, x(0), first);
    extend(result.v_mps, x(1), first);
    extend(result.phi_rad, x(2), first);
    extend(result.delta_f_radps, delta_f, first);
    extend(result.delta_f_cmd_radps, cmd.delta_f_cmd_radps, first);
    if (t >= settle_start) {
      result.settle_max_abs_p_radps = std::max(result.settle_max_abs_p_radps, std::fabs(x(0)));
      result.settle_max_abs_v_mps = std::max(result.settle_max_abs_v_mps, std::fabs(x(1)));
      result.settle_max_abs_phi_rad = std::max(result.settle_max_abs_phi_rad, std::fabs(x(2)));
    }
    if (options.record_trace) {
      result.trace.push_back({t, x(0), x(1), x(2), delta_f, cmd.delta_f_cmd_radps, cmd.delta_throttle_pct,
                              sp.roll_sp_rad, cmd.roll_ref_rad, cmd.roll_cmd_norm});
    }
    if (!x.allFinite() || x.cwiseAbs().maxCoeff() > kDivergedState) {
      result.finite = false;
      break;
    }
    if (k == n_steps) break;

    u(i_df) = delta_f;
    if (i_dt >= 0) u(i_dt) = cmd.delta_throttle_pct;
    x = d.Ad * x + d.Bd * u;
    delta_f = a_flap * delta_f + b_flap * cmd.delta_f_cmd_radps;
  }
  result.counters = controller.counters();
  return result;
}

}  // namespace nimble
