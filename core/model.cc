#include "core/model.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include <unsupported/Eigen/MatrixFunctions>

namespace nimble {
namespace {

struct InputInfo {
  const char* name;
  const char* suffix;  // derivative suffix: L_<suffix>
  const char* unit;
};

constexpr InputInfo kInputs[] = {
    {"delta_f", "df", "rad/s"},
    {"delta_t", "dt", "%"},
    {"delta_d", "dd", "rad"},
    {"delta_w", "dw", "rad"},
};

const InputInfo& input_info(const std::string& input) {
  for (const auto& info : kInputs) {
    if (input == info.name) return info;
  }
  throw std::invalid_argument("unknown input '" + input + "'");
}

/// Letters of the force/moment equations of each structure, e.g. {L, Y}.
std::vector<std::string> equation_letters(Structure s) {
  switch (s) {
    case Structure::kLateral3: return {"L", "Y"};
    case Structure::kLateral4: return {"L", "N", "Y"};
    case Structure::kLongitudinal: return {"M", "X", "Z"};
    case Structure::kBlackbox3:
    case Structure::kBlackbox4: return {};  // no force or moment equations: rows of A and B
  }
  return {};
}

/// States that derivatives are taken with respect to (the rates and velocities).
std::vector<std::string> derivative_states(Structure s) {
  switch (s) {
    case Structure::kLateral3: return {"p", "v"};
    case Structure::kLateral4: return {"p", "r", "v"};
    case Structure::kLongitudinal: return {"q", "u", "w"};
    case Structure::kBlackbox3: return {"p", "v", "phi"};
    case Structure::kBlackbox4: return {"p", "r", "v", "phi"};
  }
  return {};
}

}  // namespace

bool is_blackbox(Structure s) { return s == Structure::kBlackbox3 || s == Structure::kBlackbox4; }

bool has_yaw_rate(Structure s) { return s == Structure::kLateral4 || s == Structure::kBlackbox4; }

std::string to_string(Structure s) {
  switch (s) {
    case Structure::kLateral3: return "lateral3";
    case Structure::kLateral4: return "lateral4";
    case Structure::kLongitudinal: return "longitudinal";
    case Structure::kBlackbox3: return "blackbox3";
    case Structure::kBlackbox4: return "blackbox4";
  }
  return "?";
}

Structure structure_from_string(const std::string& name) {
  if (name == "lateral3") return Structure::kLateral3;
  if (name == "lateral4") return Structure::kLateral4;
  if (name == "longitudinal") return Structure::kLongitudinal;
  if (name == "blackbox3") return Structure::kBlackbox3;
  if (name == "blackbox4") return Structure::kBlackbox4;
  throw std::invalid_argument("unknown structure '" + name + "'");
}

const std::vector<std::string>& state_names(Structure s) {
  static const std::vector<std::string> lat3{"p", "v", "phi"};
  static const std::vector<std::string> lat4{"p", "r", "v", "phi"};
  static const std::vector<std::string> lon{"q", "u", "w", "theta"};
  switch (s) {
    case Structure::kLateral3:
    case Structure::kBlackbox3: return lat3;
    case Structure::kLateral4:
    case Structure::kBlackbox4: return lat4;
    case Structure::kLongitudinal: return lon;
  }
  return lat3;
}

const std::vector<std::string>& state_units(Structure s) {
  static const std::vector<std::string> lat3{"rad/s", "m/s", "rad"};
  static const std::vector<std::string> lat4{"rad/s", "rad/s", "m/s", "rad"};
  static const std::vector<std::string> lon{"rad/s", "m/s", "m/s", "rad"};
  switch (s) {
    case Structure::kLateral3:
    case Structure::kBlackbox3: return lat3;
    case Structure::kLateral4:
    case Structure::kBlackbox4: return lat4;
    case Structure::kLongitudinal: return lon;
  }
  return lat3;
}

std::vector<std::string> stability_derivative_names(Structure s) {
  std::vector<std::string> out;
  if (is_blackbox(s)) {
    for (const auto& row : state_names(s)) {
      for (const auto& column : state_names(s)) out.push_back(blackbox_a_name(row, column));
    }
    return out;
  }
  for (const auto& eq : equation_letters(s)) {
    for (const auto& x : derivative_states(s)) out.push_back(eq + x);
  }
  return out;
}

std::vector<std::string> control_derivative_names(Structure s, const std::string& input) {
  const InputInfo& info = input_info(input);
  std::vector<std::string> out;
  if (is_blackbox(s)) {
    for (const auto& row : state_names(s)) out.push_back(blackbox_b_name(row, input));
    return out;
  }
  for (const auto& eq : equation_letters(s)) out.push_back(eq + "_" + info.suffix);
  return out;
}

const std::vector<std::string>& known_inputs() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const auto& info : kInputs) v.push_back(info.name);
    return v;
  }();
  return names;
}

std::string input_unit(const std::string& input) { return input_info(input).unit; }

std::string input_suffix(const std::string& input) { return input_info(input).suffix; }

std::string blackbox_a_name(const std::string& row, const std::string& column) { return "a_" + row + "_" + column; }

std::string blackbox_b_name(const std::string& row, const std::string& input) {
  return "b_" + row + "_" + input_suffix(input);
}

double DerivativeModel::at(const std::string& key) const {
  const auto it = derivatives.find(key);
  if (it == derivatives.end()) {
    throw std::out_of_range("model '" + name + "' has no derivative '" + key + "'");
  }
  return it->second;
}

DerivativeModel model_from_config(ConfigMap& map) {
  DerivativeModel m;
  m.file = map.file();
  m.name = map.get_string("name");
  m.source = map.get_string("source");
  m.structure = structure_from_string(
      map.get_enum("structure", {"lateral3", "lateral4", "longitudinal", "blackbox3", "blackbox4"}));

  const std::string vehicle = map.get_string("vehicle");
  const std::filesystem::path vehicle_path(vehicle);
  m.vehicle_file = vehicle_path.is_absolute()
                       ? vehicle
                       : (std::filesystem::path(map.directory()) / vehicle_path).lexically_normal().string();

  if (m.structure == Structure::kLateral4) {
    m.coupling = map.get_enum("roll_yaw_coupling", {"full", "decoupled"}) == "full" ? RollYawCoupling::kFull
                                                                                    : RollYawCoupling::kDecoupled;
  }

  m.inputs = map.get_string_list("inputs");
  if (m.inputs.empty()) map.fail("inputs", "must name at least one input");
  for (std::size_t i = 0; i < m.inputs.size(); ++i) {
    bool known = false;
    for (const auto& k : known_inputs()) known = known || (k == m.inputs[i]);
    if (!known) {
      map.fail("inputs", "unknown input '" + m.inputs[i] + "' (known: delta_f, delta_t, delta_d, delta_w)");
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (m.inputs[j] == m.inputs[i]) map.fail("inputs", "input '" + m.inputs[i] + "' listed twice");
    }
  }

  ConfigMap trim = map.get_map("trim");
  m.trim.u0_mps = trim.get_double("u0_mps");
  m.trim.w0_mps = trim.get_double("w0_mps");
  m.trim.theta0_rad = trim.get_double("theta0_rad", Range::closed(-M_PI / 2 + 1e-6, M_PI / 2 - 1e-6));
  m.trim.phi0_rad = trim.get_double("phi0_rad", Range::closed(-M_PI, M_PI));
  trim.finish();

  // Exactly the derivatives the structure and inputs need: no more, no fewer.
  ConfigMap derivs = map.get_map("derivatives");
  std::vector<std::string> required = stability_derivative_names(m.structure);
  for (const auto& input : m.inputs) {
    for (const auto& n : control_derivative_names(m.structure, input)) required.push_back(n);
  }
  for (const auto& n : required) m.derivatives[n] = derivs.get_double(n);
  derivs.finish();

  if (map.has("published")) {
    ConfigMap pub = map.get_map("published");
    if (pub.has("eigenvalues")) {
      const YAML::Node list = pub.get_node("eigenvalues");
      if (!list.IsSequence()) pub.fail("eigenvalues", "must be a list of [re, im] pairs");
      for (const auto& pair : list) {
        if (!pair.IsSequence() || pair.size() != 2) {
          pub.fail("eigenvalues", "must be a list of [re, im] pairs");
        }
        try {
          m.published_eigenvalues.emplace_back(pair[0].as<double>(), pair[1].as<double>());
        } catch (const YAML::Exception&) {
          pub.fail("eigenvalues", "must be a list of numeric [re, im] pairs");
        }
      }
    }
    if (pub.has("sigma")) {
      ConfigMap sigma = pub.get_map("sigma");
      for (const auto& key : sigma.keys()) {
        if (m.derivatives.count(key) == 0) {
          sigma.fail(key, "standard deviation given for a derivative the model does not have");
        }
        m.published_sigma[key] = sigma.get_double(key, Range::non_negative());
      }
      sigma.finish();
    }
    pub.finish();
  }
  if (map.has("effects")) {
    if (is_blackbox(m.structure)) {
      map.fail("effects",
               "a black-box structure takes no effects: they act on forces and moments, which it does not have");
    }
    ConfigMap effects = map.get_map("effects");
    for (const auto& name : effects.keys()) {
      ConfigMap params = effects.get_map(name);
      for (const auto& key : params.keys()) m.effects[name][key] = params.get_double(key);
      params.finish();
    }
    effects.finish();
  }
  if (map.has("terms")) {
    if (m.structure == Structure::kLongitudinal) map.fail("terms", "the longitudinal structure takes no terms");
    if (is_blackbox(m.structure)) {
      map.fail("terms", "a black-box structure takes no terms: its rows are state derivatives, not forces or moments");
    }
    m.terms = terms_from_config(map, "terms", model_term_equations(m.structure), term_signal_names());
  }
  map.finish();
  return m;
}

std::vector<std::string> model_term_equations(Structure s) {
  switch (s) {
    case Structure::kLateral3: return {"L", "Y"};
    case Structure::kLateral4: return {"L", "N", "Y"};
    case Structure::kLongitudinal:
    case Structure::kBlackbox3:
    case Structure::kBlackbox4: return {};
  }
  return {};
}

DerivativeModel load_model(const std::string& file) {
  ConfigMap map = ConfigMap::load_file(file);
  return model_from_config(map);
}

StateSpace build_state_space(const DerivativeModel& model, const Vehicle& vehicle) {
  StateSpace ss;
  ss.states = state_names(model.structure);
  ss.state_units = state_units(model.structure);
  ss.inputs = model.inputs;
  for (const auto& in : model.inputs) ss.input_units.push_back(input_unit(in));

  const std::size_t n = ss.states.size();
  const std::size_t m = ss.inputs.size();
  ss.A = Eigen::MatrixXd::Zero(n, n);
  ss.B = Eigen::MatrixXd::Zero(n, m);

  const double mass = vehicle.mass_kg;
  const double g = vehicle.gravity_mps2;
  const double Ic = vehicle.Ic();
  const double Ixx = vehicle.Ixx_kgm2, Izz = vehicle.Izz_kgm2, Ixz = vehicle.Ixz_kgm2;
  const Trim& t = model.trim;
  const auto d = [&](const std::string& key) { return model.at(key); };

  switch (model.structure) {
    case Structure::kBlackbox3:
    case Structure::kBlackbox4: {
      // Every entry free (Eq C.30 / C.37): read as they are.
      for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t k = 0; k < n; ++k) ss.A(i, k) = d(blackbox_a_name(ss.states[i], ss.states[k]));
        for (std::size_t j = 0; j < m; ++j) ss.B(i, j) = d(blackbox_b_name(ss.states[i], ss.inputs[j]));
      }
      break;
    }
    case Structure::kLateral3: {
      // x = [p v phi]; pdot = Izz/Ic * L, vdot = Y/m + w0 p + g cos(theta0) cos(phi0) phi.
      const double kL = Izz / Ic;
      ss.A << kL * d("Lp"), kL * d("Lv"), 0.0, d("Yp") / mass + t.w0_mps, d("Yv") / mass,
          g * std::cos(t.theta0_rad) * std::cos(t.phi0_rad), 1.0, 0.0, 0.0;
      for (std::size_t j = 0; j < m; ++j) {
        const auto names = control_derivative_names(model.structure, ss.inputs[j]);
        ss.B(0, j) = kL * d(names[0]);
        ss.B(1, j) = d(names[1]) / mass;
      }
      break;
    }
    case Structure::kLateral4: {
      // x = [p r v phi] (Eq B.16). Rows of the moment equations mix L and N
      // through the inertia; the decoupled form (Eq 8.7) drops the Ixz terms.
      const bool full = model.coupling == RollYawCoupling::kFull;
      const double pL = Izz / Ic, pN = full ? Ixz / Ic : 0.0;
      const double rL = full ? Ixz / Ic : 0.0, rN = Ixx / Ic;
      const char* xs[] = {"p", "r", "v"};
      for (int k = 0; k < 3; ++k) {
        const std::string s = xs[k];
        ss.A(0, k) = pL * d("L" + s) + pN * d("N" + s);
        ss.A(1, k) = rL * d("L" + s) + rN * d("N" + s);
        ss.A(2, k) = d("Y" + s) / mass;
      }
      ss.A(2, 0) += t.w0_mps;
      ss.A(2, 1) -= t.u0_mps;
      ss.A(2, 3) = g * std::cos(t.theta0_rad) * std::cos(t.phi0_rad);
      ss.A(3, 0) = 1.0;
      ss.A(3, 1) = std::tan(t.theta0_rad) * std::cos(t.phi0_rad);
      for (std::size_t j = 0; j < m; ++j) {
        const auto names = control_derivative_names(model.structure, ss.inputs[j]);  // L, N, Y
        ss.B(0, j) = pL * d(names[0]) + pN * d(names[1]);
        ss.B(1, j) = rL * d(names[0]) + rN * d(names[1]);
        ss.B(2, j) = d(names[2]) / mass;
      }
      break;
    }
    case Structure::kLongitudinal: {
      // x = [q u w theta] (Eq B.15).
      const double Iyy = vehicle.Iyy_kgm2;
      ss.A << d("Mq") / Iyy, d("Mu") / Iyy, d("Mw") / Iyy, 0.0, d("Xq") / mass - t.w0_mps, d("Xu") / mass,
          d("Xw") / mass, -g * std::cos(t.theta0_rad), d("Zq") / mass + t.u0_mps, d("Zu") / mass, d("Zw") / mass,
          -g * std::sin(t.theta0_rad) * std::cos(t.phi0_rad), std::cos(t.phi0_rad), 0.0, 0.0, 0.0;
      for (std::size_t j = 0; j < m; ++j) {
        const auto names = control_derivative_names(model.structure, ss.inputs[j]);  // M, X, Z
        ss.B(0, j) = d(names[0]) / Iyy;
        ss.B(1, j) = d(names[1]) / mass;
        ss.B(2, j) = d(names[2]) / mass;
      }
      break;
    }
  }
  return ss;
}

Eigen::VectorXd term_state_gain(const DerivativeModel& model, const Vehicle& vehicle, const std::string& equation) {
  const double Ixx = vehicle.Ixx_kgm2, Izz = vehicle.Izz_kgm2, Ixz = vehicle.Ixz_kgm2, Ic = vehicle.Ic();
  const double mass = vehicle.mass_kg;
  if (model.structure == Structure::kLateral3) {
    if (equation == "L") return Eigen::Vector3d(Izz / Ic, 0.0, 0.0);
    if (equation == "Y") return Eigen::Vector3d(0.0, 1.0 / mass, 0.0);
  } else if (model.structure == Structure::kLateral4) {
    const bool full = model.coupling == RollYawCoupling::kFull;
    if (equation == "L") return Eigen::Vector4d(Izz / Ic, full ? Ixz / Ic : 0.0, 0.0, 0.0);
    if (equation == "N") return Eigen::Vector4d(full ? Ixz / Ic : 0.0, Ixx / Ic, 0.0, 0.0);
    if (equation == "Y") return Eigen::Vector4d(0.0, 0.0, 1.0 / mass, 0.0);
  }
  throw std::invalid_argument("model " + model.name + " (" + to_string(model.structure) + ") has no term equation '" +
                              equation + "'");
}

DerivativeModel plant_equivalent(const DerivativeModel& model, const Vehicle& vehicle,
                                 double* kinematic_row_difference) {
  if (kinematic_row_difference) *kinematic_row_difference = 0.0;
  if (!is_blackbox(model.structure)) return model;
  const bool yaw = has_yaw_rate(model.structure);
  const Trim& t = model.trim;
  const double mass = vehicle.mass_kg, Ic = vehicle.Ic();
  const double to_L = Ic / vehicle.Izz_kgm2, to_N = Ic / vehicle.Ixx_kgm2;
  DerivativeModel out = model;
  out.structure = yaw ? Structure::kLateral4 : Structure::kLateral3;
  out.coupling = RollYawCoupling::kDecoupled;
  out.derivatives.clear();
  out.published_sigma.clear();
  const auto a = [&](const std::string& row, const std::string& column) {
    return model.at(blackbox_a_name(row, column));
  };
  // The plant's own linearised terms of v-dot (Eq C.10): w0 p - u0 r + g cos(theta0) cos(phi0) phi.
  const double own_vp = t.w0_mps, own_vr = -t.u0_mps;
  const double own_vphi = vehicle.gravity_mps2 * std::cos(t.theta0_rad) * std::cos(t.phi0_rad);
  std::vector<std::string> xs{"p", "v"};
  if (yaw) xs = {"p", "r", "v"};
  for (const auto& x : xs) {
    out.derivatives["L" + x] = to_L * a("p", x);
    if (yaw) out.derivatives["N" + x] = to_N * a("r", x);
    const double own = x == "p" ? own_vp : x == "r" ? own_vr : 0.0;
    out.derivatives["Y" + x] = mass * (a("v", x) - own);
  }
  for (const auto& input : model.inputs) {
    const std::string suffix = input_suffix(input);
    out.derivatives["L_" + suffix] = to_L * model.at(blackbox_b_name("p", input));
    if (yaw) out.derivatives["N_" + suffix] = to_N * model.at(blackbox_b_name("r", input));
    out.derivatives["Y_" + suffix] = mass * model.at(blackbox_b_name("v", input));
  }
  // The phi column: a moment or force proportional to the roll angle's deviation from trim.
  char phi_text[64];
  std::snprintf(phi_text, sizeof phi_text, "phi - %.17g", t.phi0_rad);
  const TermExpression dphi = TermExpression::parse(t.phi0_rad == 0.0 ? std::string("phi") : std::string(phi_text));
  const auto add_term = [&](const std::string& equation, double coefficient) {
    if (coefficient != 0.0) out.terms.push_back(Term{equation, dphi, coefficient, model.file});
  };
  add_term("L", to_L * a("p", "phi"));
  if (yaw) add_term("N", to_N * a("r", "phi"));
  add_term("Y", mass * (a("v", "phi") - own_vphi));
  if (kinematic_row_difference) {
    double worst = 0.0;
    for (const auto& x : state_names(model.structure)) {
      double kinematic = x == "p" ? 1.0 : 0.0;
      if (x == "r") kinematic = std::tan(t.theta0_rad) * std::cos(t.phi0_rad);
      worst = std::max(worst, std::abs(a("phi", x) - kinematic));
    }
    for (const auto& input : model.inputs) worst = std::max(worst, std::abs(model.at(blackbox_b_name("phi", input))));
    *kinematic_row_difference = worst;
  }
  return out;
}

DiscreteStateSpace discretize_zoh(const StateSpace& ss, double dt_s) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) {
    throw std::invalid_argument("discretize_zoh: dt_s must be positive and finite");
  }
  const Eigen::Index n = ss.A.rows();
  const Eigen::Index m = ss.B.cols();
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n + m, n + m);
  M.topLeftCorner(n, n) = ss.A * dt_s;
  M.topRightCorner(n, m) = ss.B * dt_s;
  const Eigen::MatrixXd E = M.exp();
  DiscreteStateSpace out;
  out.Ad = E.topLeftCorner(n, n);
  out.Bd = E.topRightCorner(n, m);
  out.dt_s = dt_s;
  return out;
}

}  // namespace nimble
