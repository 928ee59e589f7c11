#include "turbulence/dryden.h"

#include <cmath>
#include <stdexcept>

namespace nimble::turbulence {
namespace {

void require_positive(const char* who, const char* what, double x) {
  if (!(x > 0.0) || !std::isfinite(x)) {
    throw std::invalid_argument(std::string(who) + ": " + what + " must be > 0 and finite, got " + std::to_string(x));
  }
}

LinearSystem single_input_output(Eigen::MatrixXd A, Eigen::MatrixXd B, Eigen::MatrixXd C, const std::string& output) {
  LinearSystem s;
  s.A = std::move(A);
  s.B = std::move(B);
  s.C = std::move(C);
  s.D = Eigen::MatrixXd::Zero(1, 1);
  s.inputs = {"w"};
  s.outputs = {output};
  for (Eigen::Index i = 0; i < s.A.rows(); ++i) s.states.push_back(output + "_x" + std::to_string(i + 1));
  s.validate();
  return s;
}

}  // namespace

ShapingFilter time_based_first_order(double sigma, double T_s) {
  require_positive("time_based_first_order", "sigma", sigma);
  require_positive("time_based_first_order", "T", T_s);
  ShapingFilter f;
  f.name = "Dryden first order (time based)";
  f.system = single_input_output(Eigen::MatrixXd::Constant(1, 1, -1.0 / T_s),
                                 Eigen::MatrixXd::Constant(1, 1, sigma * std::sqrt(2.0 / T_s)),
                                 Eigen::MatrixXd::Constant(1, 1, 1.0), "gust");
  f.psd = [sigma, T_s](double w) { return 2.0 * sigma * sigma * T_s / (1.0 + w * w * T_s * T_s); };
  f.variance = sigma * sigma;
  return f;
}

ShapingFilter time_based_second_order(double sigma, double T_s) {
  require_positive("time_based_second_order", "sigma", sigma);
  require_positive("time_based_second_order", "T", T_s);
  // (1 + T s)^2 = T^2 (s^2 + 2 s / T + 1 / T^2): controllable canonical form.
  Eigen::MatrixXd A(2, 2), B(2, 1), C(1, 2);
  A << 0.0, 1.0, -1.0 / (T_s * T_s), -2.0 / T_s;
  B << 0.0, 1.0;
  const double k = sigma * std::sqrt(T_s) / (T_s * T_s);
  C << k, k * std::sqrt(3.0) * T_s;
  ShapingFilter f;
  f.name = "Dryden second order (time based)";
  f.system = single_input_output(A, B, C, "gust");
  f.psd = [sigma, T_s](double w) {
    const double x2 = w * w * T_s * T_s;
    return sigma * sigma * T_s * (1.0 + 3.0 * x2) / ((1.0 + x2) * (1.0 + x2));
  };
  f.variance = sigma * sigma;
  return f;
}

ShapingFilter dryden_longitudinal(double sigma_mps, double L_m, double V_mps) {
  require_positive("dryden_longitudinal", "L", L_m);
  require_positive("dryden_longitudinal", "V", V_mps);
  ShapingFilter f = time_based_first_order(sigma_mps, L_m / V_mps);
  f.name = "Dryden u_g (MIL-F-8785C / MIL-HDBK-1797)";
  f.system.outputs = {"u_g"};
  return f;
}

ShapingFilter dryden_lateral(double sigma_mps, double L_m, double V_mps, DrydenStandard standard) {
  require_positive("dryden_lateral", "L", L_m);
  require_positive("dryden_lateral", "V", V_mps);
  const double scale = standard == DrydenStandard::kMilHdbk1797 ? 2.0 : 1.0;
  ShapingFilter f = time_based_second_order(sigma_mps, scale * L_m / V_mps);
  f.name = standard == DrydenStandard::kMilHdbk1797 ? "Dryden v_g (MIL-HDBK-1797)" : "Dryden v_g (MIL-F-8785C)";
  f.system.outputs = {"v_g"};
  return f;
}

ShapingFilter dryden_vertical(double sigma_mps, double L_m, double V_mps, DrydenStandard standard) {
  ShapingFilter f = dryden_lateral(sigma_mps, L_m, V_mps, standard);
  f.name = standard == DrydenStandard::kMilHdbk1797 ? "Dryden w_g (MIL-HDBK-1797)" : "Dryden w_g (MIL-F-8785C)";
  f.system.outputs = {"w_g"};
  return f;
}

PracticalFilterCoefficients practical_asymmetric_coefficients(double V_mps, double L_m, double ta, double tb, double tc,
                                                              double I0) {
  const char* who = "practical_asymmetric_coefficients";
  require_positive(who, "V", V_mps);
  require_positive(who, "L", L_m);
  require_positive(who, "ta", ta);
  require_positive(who, "tb", tb);
  require_positive(who, "I0", I0);
  if (!(tc >= 0.0)) throw std::invalid_argument(std::string(who) + ": tc must be >= 0");
  const double r = V_mps / L_m;
  const double p = ta * tb;
  PracticalFilterCoefficients c;
  c.a1 = -r * r / p;
  c.a2 = -(ta + tb) * r / p;
  c.b1 = tc * std::sqrt(I0 * r) / p;
  c.b2 = (1.0 - tc * (ta + tb) / p) * std::sqrt(I0 * r * r * r) / p;
  return c;
}

PracticalFilterCoefficients practical_beta_g_coefficients(double sigma_mps, double V_mps, double L_m) {
  const char* who = "practical_beta_g_coefficients";
  require_positive(who, "sigma", sigma_mps);
  require_positive(who, "V", V_mps);
  require_positive(who, "L", L_m);
  const double r = V_mps / L_m;
  PracticalFilterCoefficients c;
  c.a1 = -r * r;
  c.a2 = -2.0 * r;
  c.b1 = (sigma_mps / V_mps) * std::sqrt(3.0 * r);
  c.b2 = (1.0 - 2.0 * std::sqrt(3.0)) * (sigma_mps / V_mps) * std::sqrt(r * r * r);
  return c;
}

ShapingFilter practical_filter(const std::string& name, const PracticalFilterCoefficients& c) {
  if (!(c.a1 < 0.0) || !(c.a2 < 0.0)) {
    throw std::invalid_argument("practical_filter " + name + ": a1 and a2 must be < 0 (stable filter)");
  }
  Eigen::MatrixXd A(2, 2), B(2, 1), C(1, 2);
  A << 0.0, 1.0, c.a1, c.a2;
  B << c.b1, c.b2;
  C << 1.0, 0.0;
  ShapingFilter f;
  f.name = name;
  f.system = single_input_output(A, B, C, name);
  // H(s) = (b1 s + b2 - a2 b1) / (s^2 - a2 s - a1)
  const double n0 = c.b2 - c.a2 * c.b1;
  f.psd = [c, n0](double w) {
    const double re = -c.a1 - w * w;
    const double im = -c.a2 * w;
    return (c.b1 * c.b1 * w * w + n0 * n0) / (re * re + im * im);
  };
  // (1/2pi) int |(b1 s + n0)/(s^2 + d1 s + d0)|^2 d omega = (b1^2 d0 + n0^2) / (2 d0 d1)
  const double d0 = -c.a1, d1 = -c.a2;
  f.variance = (c.b1 * c.b1 * d0 + n0 * n0) / (2.0 * d0 * d1);
  return f;
}

}  // namespace nimble::turbulence
