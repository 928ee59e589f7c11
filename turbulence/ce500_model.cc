#include "turbulence/ce500_model.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace nimble::turbulence {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

// State and input indices.
enum State : Eigen::Index { kBeta = 0, kPhi, kP, kR, kUg, kUgStar, kAg, kAgStar, kBg, kBgStar };
enum Input : Eigen::Index { kDa = 0, kDr, kW1, kW3, kW2 };

const std::vector<std::string>& state_names() {
  static const std::vector<std::string> names = {"beta", "phi",     "pb/2V",    "rb/2V",  "u_g",
                                                 "u_g*", "alpha_g", "alpha_g*", "beta_g", "beta_g*"};
  return names;
}

const std::vector<std::string>& input_names() {
  static const std::vector<std::string> names = {"delta_a", "delta_r", "w1", "w3", "w2"};
  return names;
}

/// Writes the three gust filters into A and B (rows 4..9).
void add_filters(const Ce500Coefficients& k, Eigen::MatrixXd& A, Eigen::MatrixXd& B) {
  const auto put = [&](Eigen::Index row, Eigen::Index input, const PracticalFilterCoefficients& c) {
    A(row, row + 1) = 1.0;
    A(row + 1, row) = c.a1;
    A(row + 1, row + 1) = c.a2;
    B(row, input) = c.b1;
    B(row + 1, input) = c.b2;
  };
  put(kUg, kW1, k.u_g);
  put(kAg, kW3, k.alpha_g);
  put(kBg, kW2, k.beta_g);
}

/// The five outputs on the 10 states, given the side-force row (beta_dot of the full model).
void set_outputs(const Ce500Config& config, const Eigen::RowVectorXd& side_force_row,
                 const Eigen::RowVectorXd& side_force_input_row, LinearSystem& sys) {
  const double V = config.flight.V_mps;
  const double two_v_over_b = 2.0 * V / config.flight.b_m;
  sys.C = Eigen::MatrixXd::Zero(5, kCe500States);
  sys.D = Eigen::MatrixXd::Zero(5, sys.B.cols());
  sys.C(0, kBeta) = kRadToDeg;
  sys.C(1, kPhi) = kRadToDeg;
  sys.C(2, kP) = 1.0;
  sys.C(3, kR) = 1.0;
  sys.C.row(4) = V * side_force_row;
  sys.C(4, kR) += V * two_v_over_b;
  sys.D.row(4) = V * side_force_input_row;
  sys.outputs = {"beta [deg]", "phi [deg]", "pb/2V [-]", "rb/2V [-]", "a_y [m/s^2]"};
}

}  // namespace

Ce500Coefficients ce500_coefficients(const Ce500Config& config) {
  const auto& f = config.flight;
  const auto& d = config.derivatives;
  const auto& t = config.turbulence;
  const double V = f.V_mps, b = f.b_m, mu = f.mu_b;
  Ce500Coefficients k;
  const double vb = V / b / (2.0 * mu);
  k.y_b = vb * d.CYb;
  k.y_phi = vb * f.CL;
  k.y_p = vb * d.CYp;
  k.y_r = vb * (d.CYr - 4.0 * mu);
  k.y_dr = vb * d.CYdr;
  k.y_bg = k.y_b;
  const double den = b * 4.0 * mu * (f.KX2 * f.KZ2 - f.KXZ * f.KXZ) / V;
  const auto l = [&](double Cl, double Cn) { return (Cl * f.KZ2 + Cn * f.KXZ) / den; };
  const auto n = [&](double Cl, double Cn) { return (Cl * f.KXZ + Cn * f.KX2) / den; };
  const double Clpw = d.Clpw_per_Clp * d.Clp, Cnpw = d.Cnpw_per_Cnp * d.Cnp;
  const double Clrw = d.Clrw_per_Clr * d.Clr, Cnrw = d.Cnrw_per_Cnr * d.Cnr;
  k.l_b = l(d.Clb, d.Cnb);
  k.l_p = l(d.Clp, d.Cnp);
  k.l_r = l(d.Clr, d.Cnr);
  k.l_da = l(d.Clda, d.Cnda);
  k.l_dr = l(d.Cldr, d.Cndr);
  k.l_ug = l(-Clrw, -Cnrw);
  k.l_ag = l(Clpw, Cnpw);
  k.l_bg = k.l_b;
  k.n_b = n(d.Clb, d.Cnb);
  k.n_p = n(d.Clp, d.Cnp);
  k.n_r = n(d.Clr, d.Cnr);
  k.n_da = n(d.Clda, d.Cnda);
  k.n_dr = n(d.Cldr, d.Cndr);
  k.n_ug = n(-Clrw, -Cnrw);
  k.n_ag = n(Clpw, Cnpw);
  k.n_bg = k.n_b;
  const double sv = t.sigma_ug_mps / V, sw = t.sigma_wg_mps / V;
  k.u_g = practical_asymmetric_coefficients(V, t.Lg_m, t.tau[0], t.tau[1], t.tau[2], t.Iug0_factor * sv * sv);
  k.alpha_g = practical_asymmetric_coefficients(V, t.Lg_m, t.tau[3], t.tau[4], t.tau[5], t.Iag0_factor * sw * sw);
  k.beta_g = practical_beta_g_coefficients(t.sigma_vg_mps, V, t.Lg_m);
  return k;
}

LinearSystem ce500_full_model(const Ce500Config& config) {
  const Ce500Coefficients k = ce500_coefficients(config);
  LinearSystem s;
  s.A = Eigen::MatrixXd::Zero(kCe500States, kCe500States);
  s.B = Eigen::MatrixXd::Zero(kCe500States, 5);
  s.A.row(kBeta) << k.y_b, k.y_phi, k.y_p, k.y_r, 0, 0, 0, 0, k.y_bg, 0;
  s.A(kPhi, kP) = 2.0 * config.flight.V_mps / config.flight.b_m;
  s.A.row(kP) << k.l_b, 0, k.l_p, k.l_r, k.l_ug, 0, k.l_ag, 0, k.l_bg, 0;
  s.A.row(kR) << k.n_b, 0, k.n_p, k.n_r, k.n_ug, 0, k.n_ag, 0, k.n_bg, 0;
  s.B(kBeta, kDr) = k.y_dr;
  s.B(kP, kDa) = k.l_da;
  s.B(kP, kDr) = k.l_dr;
  s.B(kR, kDa) = k.n_da;
  s.B(kR, kDr) = k.n_dr;
  add_filters(k, s.A, s.B);
  s.states = state_names();
  s.inputs = input_names();
  set_outputs(config, s.A.row(kBeta), s.B.row(kBeta), s);
  s.validate();
  return s;
}

Eigen::RowVectorXd ce500_roll_damper_gain(const Ce500Config& config) {
  Eigen::RowVectorXd K = Eigen::RowVectorXd::Zero(kCe500States);
  K[kPhi] = config.K_phi;
  K[kP] = config.K_p;
  return K;
}

LinearSystem ce500_controlled_model(const Ce500Config& config) {
  const LinearSystem open = ce500_full_model(config);
  LinearSystem closed = close_state_feedback(open, "delta_a", ce500_roll_damper_gain(config));
  // beta_dot of the closed loop: the outputs are rebuilt from its side-force row.
  set_outputs(config, closed.A.row(kBeta), closed.B.row(kBeta), closed);
  return closed;
}

LinearSystem ce500_reduced_model(const Ce500Config& config, bool with_damper) {
  const auto& f = config.flight;
  const auto& d = config.derivatives;
  const double V = f.V_mps, b = f.b_m, mu = f.mu_b;
  Eigen::Matrix4d P = Eigen::Matrix4d::Zero();
  P(0, 0) = b / (2.0 * V);
  P(1, 1) = -b / (2.0 * V);
  P(2, 2) = -4.0 * mu * f.KX2 * b / V;
  P(2, 3) = 4.0 * mu * f.KXZ * b / V;
  P(3, 2) = 4.0 * mu * f.KXZ * b / V;  // KXZ, not the practical's misprinted KXZ^2
  P(3, 3) = -4.0 * mu * f.KZ2 * b / V;
  Eigen::Matrix4d Q;
  Q << 0, 0, 0, -1, 0, 0, -1, 0, -d.Clb, 0, -d.Clp, -d.Clr, -d.Cnb, 0, -d.Cnp, -d.Cnr;
  Eigen::Matrix<double, 4, 2> R = Eigen::Matrix<double, 4, 2>::Zero();
  R.row(2) << -d.Clda, -d.Cldr;
  R.row(3) << -d.Cnda, -d.Cndr;
  // Gust moments on (u_g, alpha_g, beta_g), in the sign convention of Q.
  const double Clpw = d.Clpw_per_Clp * d.Clp, Cnpw = d.Cnpw_per_Cnp * d.Cnp;
  const double Clrw = d.Clrw_per_Clr * d.Clr, Cnrw = d.Cnrw_per_Cnr * d.Cnr;
  Eigen::Matrix<double, 4, 6> Qg = Eigen::Matrix<double, 4, 6>::Zero();
  Qg(2, 0) = Clrw;  // -(-Clrw)
  Qg(3, 0) = Cnrw;
  Qg(2, 2) = -Clpw;
  Qg(3, 2) = -Cnpw;
  Qg(2, 4) = -d.Clb;
  Qg(3, 4) = -d.Cnb;
  const Eigen::Matrix4d Pinv = P.inverse();

  const Ce500Coefficients k = ce500_coefficients(config);
  LinearSystem s;
  s.A = Eigen::MatrixXd::Zero(kCe500States, kCe500States);
  s.B = Eigen::MatrixXd::Zero(kCe500States, 5);
  s.A.topLeftCorner(kCe500AircraftStates, kCe500AircraftStates) = Pinv * Q;
  s.A.topRightCorner(kCe500AircraftStates, kCe500States - kCe500AircraftStates) = Pinv * Qg;
  if (config.reduced_gust_columns == ReducedGustColumns::kFullModelRows) s.A(kBeta, kBg) = k.y_bg;
  s.B.topLeftCorner(kCe500AircraftStates, 2) = Pinv * R;
  add_filters(k, s.A, s.B);
  s.C = Eigen::MatrixXd::Zero(0, kCe500States);
  s.D = Eigen::MatrixXd::Zero(0, s.B.cols());
  s.states = state_names();
  s.inputs = input_names();

  const LinearSystem full = with_damper ? ce500_controlled_model(config) : ce500_full_model(config);
  if (with_damper) s = close_state_feedback(s, "delta_a", ce500_roll_damper_gain(config));
  set_outputs(config, full.A.row(kBeta), full.B.row(kBeta), s);
  s.validate();
  return s;
}

Eigen::VectorXd ce500_noise_intensity(const Ce500Config& config) {
  Eigen::VectorXd W = Eigen::VectorXd::Zero(5);
  const double w = config.excitation.intensity;
  if (config.excitation.u_g) W[kW1] = w;
  if (config.excitation.w_g) W[kW3] = w;
  if (config.excitation.v_g) W[kW2] = w;
  return W;
}

std::vector<ShapingFilter> ce500_gust_filters(const Ce500Config& config) {
  const Ce500Coefficients k = ce500_coefficients(config);
  return {practical_filter("u_g", k.u_g), practical_filter("alpha_g", k.alpha_g), practical_filter("beta_g", k.beta_g)};
}

std::vector<NamedEigenvalue> ce500_named_eigenvalues(const LinearSystem& sys) {
  if (sys.n_states() != kCe500States) throw std::invalid_argument("ce500_named_eigenvalues: need the 10-state model");
  std::vector<NamedEigenvalue> out;
  const Eigen::MatrixXd Aa = sys.A.topLeftCorner(kCe500AircraftStates, kCe500AircraftStates);
  const Eigen::EigenSolver<Eigen::MatrixXd> es(Aa);
  std::vector<int> pairs, reals;
  for (int i = 0; i < 4; ++i) {
    const auto z = es.eigenvalues()[i];
    if (z.imag() > 0.0) pairs.push_back(i);
    if (z.imag() == 0.0) reals.push_back(i);
  }
  // Of two oscillatory pairs the Dutch roll is the faster oscillation (larger imaginary part).
  int dutch = -1;
  for (const int i : pairs) {
    if (dutch < 0 || es.eigenvalues()[i].imag() > es.eigenvalues()[dutch].imag()) dutch = i;
  }
  for (int i = 0; i < 4; ++i) {
    const auto z = es.eigenvalues()[i];
    std::string name;
    if (z.imag() != 0.0) {
      // The pair's member with positive imaginary part carries the pair's index in `pairs`.
      int member = i;
      for (const int j : pairs) {
        if (std::abs(es.eigenvalues()[j] - std::conj(z)) < 1e-9 * (1.0 + std::abs(z))) member = j;
      }
      name = member == dutch ? "Dutch roll" : "roll pair (aperiodic roll and bank angle joined by the roll damper)";
    } else if (std::abs(z.real()) < 1e-9) {
      name = "bank angle (neutral)";
    } else if (reals.size() >= 2) {
      double fastest = 0.0;
      for (const int j : reals) fastest = std::max(fastest, std::abs(es.eigenvalues()[j].real()));
      name = std::abs(z.real()) == fastest ? "aperiodic roll" : "spiral";
    } else {
      name = "aperiodic roll";
    }
    if (z.real() > 0.0) name += " (unstable)";
    out.push_back({z, name});
  }
  const auto add_filter = [&](Eigen::Index row, const std::string& name) {
    const Eigen::EigenSolver<Eigen::MatrixXd> ef(Eigen::MatrixXd(sys.A.block(row, row, 2, 2)), false);
    for (int i = 0; i < 2; ++i) out.push_back({ef.eigenvalues()[i], name + " filter (gust pole)"});
  };
  add_filter(kUg, "u_g");
  add_filter(kAg, "alpha_g");
  add_filter(kBg, "beta_g");
  std::sort(out.begin(), out.end(), [](const NamedEigenvalue& a, const NamedEigenvalue& b) {
    return a.value.real() != b.value.real() ? a.value.real() > b.value.real() : a.value.imag() > b.value.imag();
  });
  return out;
}

}  // namespace nimble::turbulence
