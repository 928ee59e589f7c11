#include "plant/plant_model.h"

#include "effects/registry.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace nimble::plant {
using effects::LoadInputs;
using effects::ProcessContext;
namespace {

// State layout.
enum : int {
  kN = 0,
  kE,
  kD,  // position NED [m]
  kU,
  kV,
  kW,  // body velocity [m/s]
  kPhi,
  kTheta,
  kPsi,  // ZYX Euler angles [rad]
  kP,
  kQ,
  kR,      // body rates [rad/s]
  kFcoll,  // actual collective flapping frequency [rad/s]
  kDf,     // actual flapping-frequency difference [rad/s]
  kDd,
  kDdRate,  // dihedral servo position [rad] and rate [rad/s]
  kDw,
  kDwRate,  // wing-root servo position [rad] and rate [rad/s]
  kStates
};
static_assert(kStates == PlantModel::kStateDim, "PlantModel::kStateDim is the state layout's size");

double get_or_zero(const DerivativeModel& m, const std::string& key) {
  const auto it = m.derivatives.find(key);
  return it == m.derivatives.end() ? 0.0 : it->second;
}

Eigen::Vector4d quaternion_from_euler(double phi, double theta, double psi) {
  const double cr = std::cos(phi / 2), sr = std::sin(phi / 2);
  const double cp = std::cos(theta / 2), sp = std::sin(theta / 2);
  const double cy = std::cos(psi / 2), sy = std::sin(psi / 2);
  return {cy * cp * cr + sy * sp * sr, cy * cp * sr - sy * sp * cr, cy * sp * cr + sy * cp * sr,
          sy * cp * cr - cy * sp * sr};
}

}  // namespace

const ParamTable<PlantConfig>& plant_params() {
  using C = PlantConfig;
  static const ParamTable<C> table = {
      {"rate_hz", &C::rate_hz, Range::closed(100.0, 20000.0), "Hz",
       "integration rate, the lockstep step; whole ns per step"},
      {"truth_rate_hz", &C::truth_rate_hz, Range{0.0, 20000.0, true, false}, "Hz",
       "TRUTH publication rate; divides rate_hz"},
      {"feedback_rate_hz", &C::feedback_rate_hz, Range{0.0, 20000.0, true, false}, "Hz",
       "ACTUATOR_FB publication rate; divides rate_hz"},
      {"command_timeout_s", &C::command_timeout_s, Range{0.0, 10.0, true, false}, "s",
       "hold the safe state when commands stop this long"},
      {"command_resolution.flap_freq_radps", &C::flap_command_resolution_radps, Range::closed(0.0, 10.0), "rad/s",
       "flapping-frequency commands are rounded to this (the CAN frames' resolution)"},
      {"command_resolution.servo_rad", &C::servo_command_resolution_rad, Range::closed(0.0, 0.1), "rad",
       "servo commands are rounded to this"},
      {"collective_radps_per_pct", &C::collective_radps_per_pct, Range::positive(), "rad/s/%",
       "collective per % throttle; equals the controller's throttle_to_freq_radps_per_pct"},
      {"vertical_damping_Zw_nspm", &C::vertical_damping_Zw_nspm, Range::closed(-10.0, 0.0), "N s/m",
       "vertical damping without a longitudinal model"},
  };
  return table;
}

const ParamTable<FlapActuatorConfig>& flap_actuator_params() {
  using C = FlapActuatorConfig;
  static const ParamTable<C> table = {
      {"delta_f_gain_radps", &C::delta_f_gain_radps, Range::positive(), "rad/s",
       "delta_f = gain / (s + pole) delta_f_cmd; thesis Eq 33 scaled by 1/1.4"},
      {"pole_radps", &C::pole_radps, Range::positive(), "rad/s", "flap mechanism pole; thesis Eq 33: 12.56"},
  };
  return table;
}

const ParamTable<ServoConfig>& servo_params() {
  // y = wn^2 / (s^2 + c1 s + wn^2) u; thesis: 554.2 / (s^2 + 30.25 s + 554.2).
  static const ParamTable<ServoConfig> table = {
      {"wn2_rad2ps2", &ServoConfig::wn2_rad2ps2, Range::positive(), "1/s^2", "servo wn^2; thesis: 554.2"},
      {"c1_radps", &ServoConfig::c1_radps, Range::positive(), "1/s", "servo 2 zeta wn; thesis: 30.25"}};
  return table;
}

const ParamTable<ThrustCurve>& thrust_params() {
  using C = ThrustCurve;
  static const ParamTable<C> table = {
      {"slope_n_per_hz", &C::slope_n_per_hz, Range::positive(), "N/Hz",
       "thrust slope per wing pair; thesis Eq 4.18: 0.0114"},
      {"offset_n", &C::offset_n, Range::any(), "N", "thrust offset per wing pair; thesis Eq 4.18: 0.0449"},
      {"pairs", &C::pairs, Range::positive(), "-", "wing pairs: 2"},
  };
  return table;
}

const ParamTable<InitialState>& initial_params() {
  using C = InitialState;
  const Range rates = Range::closed(-20.0, 20.0);
  static const ParamTable<C> table = {
      {"p_radps", &C::p_radps, rates, "rad/s", "initial roll rate"},
      {"q_radps", &C::q_radps, rates, "rad/s", "initial pitch rate"},
      {"r_radps", &C::r_radps, rates, "rad/s", "initial yaw rate"},
      {"u_mps", &C::u_mps, Range::closed(-5.0, 5.0), "m/s", "initial forward speed perturbation"},
      {"v_mps", &C::v_mps, Range::closed(-5.0, 5.0), "m/s", "initial side speed"},
      {"phi_rad", &C::phi_rad, Range::closed(-1.2, 1.2), "rad", "initial roll"},
      {"theta_rad", &C::theta_rad, Range::closed(-1.2, 1.2), "rad", "initial pitch perturbation"},
  };
  return table;
}

PlantConfig plant_config_from(ConfigMap& map) {
  PlantConfig c;
  read_params(map, plant_params(), c);
  if (map.has("command_resolution")) {
    ConfigMap r = map.get_map("command_resolution");
    read_params(r, plant_params(), c, "command_resolution");
    r.finish();
  }
  for (const auto& [key, rate] :
       {std::pair<const char*, double>{"truth_rate_hz", c.truth_rate_hz}, {"feedback_rate_hz", c.feedback_rate_hz}}) {
    const double ratio = c.rate_hz / rate;
    if (std::fabs(ratio - std::round(ratio)) > 1e-9) {
      map.fail(key, "must divide rate_hz (" + std::to_string(c.rate_hz) + " Hz) into whole steps");
    }
  }
  const double period_ns = 1e9 / c.rate_hz;
  if (std::fabs(period_ns - std::round(period_ns)) > 1e-6) {
    map.fail("rate_hz", "must give a whole number of nanoseconds per step (e.g. 500, 1000, 2000)");
  }
  const auto sub = [&map](const char* key, const auto& table, auto& part) {
    if (!map.has(key)) return;
    ConfigMap m = map.get_map(key);
    read_params(m, table, part);
    m.finish();
  };
  sub("flap_actuator", flap_actuator_params(), c.flap);
  sub("servo", servo_params(), c.servo);
  sub("thrust", thrust_params(), c.thrust);
  sub("initial", initial_params(), c.initial);
  if (map.has("effects")) {
    ConfigMap e = map.get_map("effects");
    effects_from(e, c.effects);  // effects/registry.h
  }
  if (map.has("terms")) c.terms = terms_from_config(map, "terms", plant_term_equations(), term_signal_names());
  map.finish();
  return c;
}

const std::vector<std::string>& plant_term_equations() {
  static const std::vector<std::string> names{"L", "Y", "N"};
  return names;
}

std::string terms_markdown() {
  std::string out = kParamsMarkdownHeader;
  out +=
      "| `plant.terms[].equation` | - | L, Y, N | - | the equation the term adds to: roll moment L, side force Y, "
      "yaw moment N (lateral4 only) |\n";
  out +=
      "| `plant.terms[].expression` | - | the term grammar (docs/models.md, \"Terms\"); signals p, q, r, u, v, w, "
      "phi, theta, delta_f, delta_t, delta_d, delta_w | - | the expression, e.g. `p^3`, `v*abs(v)`, "
      "`lag(delta_f, 0.02)` |\n";
  out +=
      "| `plant.terms[].coefficient` | - | finite | N m (L, N) or N (Y) per unit of the expression | "
      "L, Y or N += coefficient * expression |\n";
  return out;
}

PlantModel::PlantModel(const DerivativeModel& lateral, const std::optional<DerivativeModel>& longitudinal,
                       const Vehicle& vehicle, const PlantConfig& config)
    : lat_(plant_equivalent(lateral, vehicle)), lon_(longitudinal), veh_(vehicle), cfg_(config), rng_(config.seed) {
  if (lat_.structure == Structure::kLongitudinal) {
    throw std::invalid_argument("plant: model '" + lat_.name + "' is longitudinal; the plant needs a lateral model");
  }
  if (lon_ && lon_->structure != Structure::kLongitudinal) {
    throw std::invalid_argument("plant: longitudinal model '" + lon_->name + "' has structure " +
                                to_string(lon_->structure));
  }
  dt_s_ = 1.0 / cfg_.rate_hz;
  // Every effect the lateral model's effects: section carries (rig discrepancy --model-out)
  // flies with the model's coefficients, overriding the plant file's effect of the same name;
  // dihedral_coupling and yaw_coupling set derivatives (read into the cache below);
  // kinematic_coupling and gravity_nonlinearity are in the equations of motion already; an
  // effect the plant does not know is refused. The mapping: effects/registry.h.
  apply_model_effects(lateral, cfg_.effects, lat_.derivatives);
  lateral4_ = lat_.structure == Structure::kLateral4;
  active_r_ = lateral4_;
  active_q_ = lon_.has_value();
  active_u_ = lon_.has_value();

  const auto& L = lat_;
  Lp_ = get_or_zero(L, "Lp");
  Lr_ = get_or_zero(L, "Lr");
  Lv_ = get_or_zero(L, "Lv");
  Np_ = get_or_zero(L, "Np");
  Nr_ = get_or_zero(L, "Nr");
  Nv_ = get_or_zero(L, "Nv");
  Yp_ = get_or_zero(L, "Yp");
  Yr_ = get_or_zero(L, "Yr");
  Yv_ = get_or_zero(L, "Yv");
  L_df_ = get_or_zero(L, "L_df");
  L_dt_ = get_or_zero(L, "L_dt");
  L_dd_ = get_or_zero(L, "L_dd");
  L_dw_ = get_or_zero(L, "L_dw");
  N_df_ = get_or_zero(L, "N_df");
  N_dt_ = get_or_zero(L, "N_dt");
  N_dd_ = get_or_zero(L, "N_dd");
  N_dw_ = get_or_zero(L, "N_dw");
  Y_df_ = get_or_zero(L, "Y_df");
  Y_dt_ = get_or_zero(L, "Y_dt");
  Y_dd_ = get_or_zero(L, "Y_dd");
  Y_dw_ = get_or_zero(L, "Y_dw");
  if (lon_) {
    const auto& M = *lon_;
    Mq_ = M.at("Mq");
    Mu_ = M.at("Mu");
    Mw_ = M.at("Mw");
    M_dd_ = get_or_zero(M, "M_dd");
    Xq_ = M.at("Xq");
    Xu_ = M.at("Xu");
    Xw_ = M.at("Xw");
    X_dd_ = get_or_zero(M, "X_dd");
    Zq_ = M.at("Zq");
    Zu_ = M.at("Zu");
    Zw_ = M.at("Zw");
    Z_dd_ = get_or_zero(M, "Z_dd");
  }

  // Generic terms: the plant file's, then the lateral model's.
  std::vector<Term> terms = cfg_.terms;
  const std::vector<Term> effect_terms =
      effects::effect_terms(cfg_.effects, lat_.trim);  // term effects (effects/term_effect.h)
  terms.insert(terms.end(), effect_terms.begin(), effect_terms.end());
  terms.insert(terms.end(), lat_.terms.begin(), lat_.terms.end());  // a black-box model's phi column among them
  for (const Term& term : terms) {
    const auto& eqs = plant_term_equations();
    term_programs_.emplace_back(term.expression, term_signal_names());
    term_equation_.push_back(static_cast<int>(std::find(eqs.begin(), eqs.end(), term.equation) - eqs.begin()));
    term_coefficient_.push_back(term.coefficient);
  }

  // Trim: thrust equals weight.
  const Trim& trim = lat_.trim;
  trim_thrust_n_ = veh_.mass_kg * veh_.gravity_mps2 * std::cos(trim.theta0_rad) * std::cos(trim.phi0_rad);
  f_trim_radps_ = cfg_.thrust.frequency_radps(trim_thrust_n_);

  x_ = State::Zero();
  x_[kU] = trim.u0_mps + (active_u_ ? cfg_.initial.u_mps : 0.0);
  x_[kW] = trim.w0_mps;
  x_[kPhi] = trim.phi0_rad + cfg_.initial.phi_rad;
  x_[kTheta] = trim.theta0_rad + (active_q_ ? cfg_.initial.theta_rad : 0.0);
  x_[kP] = cfg_.initial.p_radps;
  x_[kQ] = active_q_ ? cfg_.initial.q_radps : 0.0;
  x_[kR] = active_r_ ? cfg_.initial.r_radps : 0.0;
  x_[kV] = cfg_.initial.v_mps;
  x_[kFcoll] = f_trim_radps_;

  // The effects' processes, in the registry's order: the draws of the seeded ones (the
  // flapping forcing's phases, a Dryden gust's start) come from the plant's stream here.
  ProcessContext context{dt_s_, rng_, normal_};
  effects_ = make_effect_processes(cfg_.effects, context);
  update_truth(trim_command());
}

ActuatorInput PlantModel::trim_command() const { return ActuatorInput{f_trim_radps_, f_trim_radps_, 0.0, 0.0}; }

ActuatorInput PlantModel::actuated(const ActuatorInput& cmd) {
  ActuatorInput out = cmd;
  const ActuatorInput trim = trim_command();
  for (auto& effect : effects_) out = effect->command(t_s_, out, trim);
  return out;
}

double PlantModel::side_wind_mps() const {
  double wind = 0.0;
  for (const auto& effect : effects_) wind += effect->side_wind_mps();
  return wind;
}

PlantModel::State PlantModel::derivative(const State& x, const ActuatorInput& u, double t,
                                         Eigen::Vector3d* specific_force, Eigen::Vector3d* omega_dot) const {
  State dx = State::Zero();
  const double m = veh_.mass_kg, g = veh_.gravity_mps2;
  const double Ixx = veh_.Ixx_kgm2, Iyy = veh_.Iyy_kgm2, Izz = veh_.Izz_kgm2, Ixz = veh_.Ixz_kgm2;
  const double Ic = veh_.Ic();
  const Trim& trim = lat_.trim;

  const double uu = x[kU], v = x[kV], w = x[kW];
  const double phi = x[kPhi], theta = x[kTheta], psi = x[kPsi];
  const double p = x[kP], q = x[kQ], r = x[kR];

  // Actuators: collective with unity gain, delta_f per Eq 33, second-order servos.
  const double pole = cfg_.flap.pole_radps;
  const double f_cmd = 0.5 * (u.flap_freq_left_radps + u.flap_freq_right_radps);
  const double df_cmd = u.flap_freq_left_radps - u.flap_freq_right_radps;
  dx[kFcoll] = pole * (f_cmd - x[kFcoll]);
  dx[kDf] = cfg_.flap.delta_f_gain_radps * df_cmd - pole * x[kDf];
  dx[kDd] = x[kDdRate];
  dx[kDdRate] = cfg_.servo.wn2_rad2ps2 * (u.dihedral_rad - x[kDd]) - cfg_.servo.c1_radps * x[kDdRate];
  dx[kDw] = x[kDwRate];
  dx[kDwRate] = cfg_.servo.wn2_rad2ps2 * (u.wing_root_rad - x[kDw]) - cfg_.servo.c1_radps * x[kDwRate];

  const double df = x[kDf];
  const double dt_pct = (x[kFcoll] - f_trim_radps_) / cfg_.collective_radps_per_pct;
  const double dd = x[kDd], dw = x[kDw];
  const double thrust = cfg_.thrust.thrust_n(x[kFcoll]);

  // Aerodynamic perturbation forces and moments.
  // The effects act on the velocity the aerodynamics see and scale the stability derivatives.
  const double v_rel = v - side_wind_mps();
  const double du = uu - trim.u0_mps, dw_vel = w - trim.w0_mps;
  double k_speed = 1.0;
  for (const auto& effect : effects_) k_speed *= effect->stability_factor(du);

  double L = k_speed * (Lp_ * p + Lr_ * r + Lv_ * v_rel) + L_df_ * df + L_dt_ * dt_pct + L_dd_ * dd + L_dw_ * dw;
  double N = k_speed * (Np_ * p + Nr_ * r + Nv_ * v_rel) + N_df_ * df + N_dt_ * dt_pct + N_dd_ * dd + N_dw_ * dw;
  double Y = k_speed * (Yp_ * p + Yr_ * r + Yv_ * v_rel) + Y_df_ * df + Y_dt_ * dt_pct + Y_dd_ * dd + Y_dw_ * dw;
  double X = 0.0, M = 0.0, Z = cfg_.vertical_damping_Zw_nspm * dw_vel;
  if (lon_) {
    M = Mq_ * q + Mu_ * du + Mw_ * dw_vel + M_dd_ * dd;
    X = Xq_ * q + Xu_ * du + Xw_ * dw_vel + X_dd_ * dd;
    Z = Zq_ * q + Zu_ * du + Zw_ * dw_vel + Z_dd_ * dd;
  }
  // The effects' loads, in the registry's order.
  const LoadInputs effect_inputs{du, p, v_rel, flap_phase_rad_ + x_[kFcoll] * (t - t_s_), t, L_df_ * df, Y_df_ * df};
  for (const auto& effect : effects_) effect->add_loads(effect_inputs, L, Y);
  if (!term_programs_.empty()) {
    double signals[12];
    term_signals(x, signals);
    for (std::size_t i = 0; i < term_programs_.size(); ++i) {
      const double load = term_coefficient_[i] * term_programs_[i].evaluate(signals);
      (term_equation_[i] == 0 ? L : term_equation_[i] == 1 ? Y : N) += load;
    }
  }
  Z -= thrust;

  // Translational dynamics (thesis Eq 3.1), body axes.
  const double sphi = std::sin(phi), cphi = std::cos(phi), sth = std::sin(theta), cth = std::cos(theta);
  dx[kU] = active_u_ ? -(q * w - r * v) + X / m - g * sth : 0.0;
  dx[kV] = -(r * uu - p * w) + Y / m + g * cth * sphi;
  dx[kW] = -(p * v - q * uu) + Z / m + g * cth * cphi;

  // Rotational dynamics: [Ixx -Ixz; -Ixz Izz] [pdot; rdot] = [b1; b2].
  const double b1 = L - (Izz - Iyy) * q * r + Ixz * p * q;
  const double b2 = N - (Iyy - Ixx) * p * q - Ixz * q * r;
  double pdot, rdot;
  if (lateral4_ && lat_.coupling == RollYawCoupling::kDecoupled) {
    pdot = Izz / Ic * b1;  // thesis Eq 8.7: the identified L and N act decoupled
    rdot = Ixx / Ic * b2;
  } else {
    pdot = (Izz * b1 + Ixz * b2) / Ic;
    rdot = (Ixz * b1 + Ixx * b2) / Ic;
  }
  const double qdot = (M - (Ixx - Izz) * p * r - Ixz * (p * p - r * r)) / Iyy;
  dx[kP] = pdot;
  dx[kQ] = active_q_ ? qdot : 0.0;
  dx[kR] = active_r_ ? rdot : 0.0;

  // Kinematics.
  const double tth = std::tan(theta);
  dx[kPhi] = p + (q * sphi + r * cphi) * tth;
  // Without a longitudinal model the vehicle's own pitch loop holds theta at trim (q is not a
  // state here; theta_dot = q cos(phi) - r sin(phi) with q = 0 would let the yaw rate tilt it).
  dx[kTheta] = active_q_ ? q * cphi - r * sphi : 0.0;
  dx[kPsi] = (q * sphi + r * cphi) / cth;
  const double spsi = std::sin(psi), cpsi = std::cos(psi);
  Eigen::Matrix3d R;  // body to NED, ZYX
  R << cth * cpsi, sphi * sth * cpsi - cphi * spsi, cphi * sth * cpsi + sphi * spsi, cth * spsi,
      sphi * sth * spsi + cphi * cpsi, cphi * sth * spsi - sphi * cpsi, -sth, sphi * cth, cphi * cth;
  dx.segment<3>(kN) = R * Eigen::Vector3d(uu, v, w);

  if (specific_force) *specific_force = Eigen::Vector3d(X / m, Y / m, Z / m);
  if (omega_dot) *omega_dot = Eigen::Vector3d(dx[kP], dx[kQ], dx[kR]);
  return dx;
}

void PlantModel::term_signals(const State& x, double* out) const {
  // In term_signal_names() order: p q r u v w phi theta delta_f delta_t delta_d delta_w.
  out[0] = x[kP];
  out[1] = x[kQ];
  out[2] = x[kR];
  out[3] = x[kU];
  out[4] = x[kV];
  out[5] = x[kW];
  out[6] = x[kPhi];
  out[7] = x[kTheta];
  out[8] = x[kDf];
  out[9] = (x[kFcoll] - f_trim_radps_) / cfg_.collective_radps_per_pct;
  out[10] = x[kDd];
  out[11] = x[kDw];
}

void PlantModel::step(const ActuatorInput& cmd_in) {
  const ActuatorInput cmd = actuated(cmd_in);
  const double h = dt_s_;
  double term_start[12];
  if (!term_programs_.empty()) term_signals(x_, term_start);
  const State k1 = derivative(x_, cmd, t_s_, nullptr, nullptr);
  const State k2 = derivative(x_ + 0.5 * h * k1, cmd, t_s_ + 0.5 * h, nullptr, nullptr);
  const State k3 = derivative(x_ + 0.5 * h * k2, cmd, t_s_ + 0.5 * h, nullptr, nullptr);
  const State k4 = derivative(x_ + h * k3, cmd, t_s_ + h, nullptr, nullptr);
  const double f_before = x_[kFcoll];
  x_ += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
  flap_phase_rad_ = std::fmod(flap_phase_rad_ + 0.5 * (f_before + x_[kFcoll]) * h, 2.0 * M_PI);
  t_s_ += h;
  // The terms' lags and backlashes move over the step with the step's starting signals held.
  for (auto& program : term_programs_) {
    program.evaluate(term_start);
    program.advance(h);
  }

  for (auto& effect : effects_) effect->step(h, rng_, normal_);
  update_truth(cmd);
}

void PlantModel::update_truth(const ActuatorInput& u) {
  Eigen::Vector3d sf, wdot;
  derivative(x_, u, t_s_, &sf, &wdot);
  Truth& tr = truth_;
  tr.time_s = t_s_;
  tr.position_ned_m = x_.segment<3>(kN);
  tr.velocity_body_mps = x_.segment<3>(kU);
  tr.euler_rad = x_.segment<3>(kPhi);
  tr.quaternion_wxyz = quaternion_from_euler(x_[kPhi], x_[kTheta], x_[kPsi]);
  tr.omega_body_radps = x_.segment<3>(kP);
  tr.specific_force_body_mps2 = sf;
  tr.angular_accel_body_radps2 = wdot;
  tr.flap_freq_left_radps = x_[kFcoll] + 0.5 * x_[kDf];
  tr.flap_freq_right_radps = x_[kFcoll] - 0.5 * x_[kDf];
  tr.delta_f_radps = x_[kDf];
  tr.throttle_pct = (x_[kFcoll] - f_trim_radps_) / cfg_.collective_radps_per_pct;
  tr.dihedral_rad = x_[kDd];
  tr.wing_root_rad = x_[kDw];
  tr.gust_v_mps = side_wind_mps();
}

}  // namespace nimble::plant
