// Unit tests of the linear model core against the thesis's published numbers.

#include <algorithm>
#include <cmath>
#include <complex>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "core/model.h"
#include "core/modes.h"
#include "core/vehicle.h"
#include "tests/support/configs.h"

using namespace nimble;

namespace {

using nimble::test::kConfigs;

// Published eigenvalues, thesis Table 9.5 (typed here independently of the YAML files).
// Per-eigenvalue tolerance: 2 %, except sets 3 and 5 whose oscillatory pair the
// published derivatives do not reproduce to 2 % (2.04 % and 2.56 %; even the best
// choice of every derivative and w0 inside its printed rounding interval leaves
// 1.84 % and 2.21 %), so their table values are checked at 3 %. All five sets are
// also checked at 2 % of the spectral radius (normwise eigenvalue error).
struct PublishedSet {
  int set;
  double real_root;
  double osc_re;
  double osc_im;
  double tolerance;
};
const PublishedSet kTable95[] = {
    {1, -5.18, 0.32, 2.73, 0.02}, {2, -6.84, 0.39, 3.74, 0.02}, {3, -7.19, 0.97, 4.26, 0.03},
    {4, -9.85, 1.36, 5.75, 0.02}, {5, -7.45, 0.30, 3.65, 0.03},
};

double nearest_distance(const std::vector<std::complex<double>>& eig, std::complex<double> target) {
  double best = INFINITY;
  for (const auto& z : eig) best = std::min(best, std::abs(z - target));
  return best;
}

double nearest_relative_error(const std::vector<std::complex<double>>& eig, std::complex<double> target) {
  return nearest_distance(eig, target) / std::abs(target);
}

}  // namespace

TEST_CASE("eigenvalues of the five identification sets match thesis Table 9.5", "[model]") {
  for (const auto& pub : kTable95) {
    const std::string file = kConfigs + "models/nimble_lateral_set" + std::to_string(pub.set) + ".yaml";
    INFO("model " << file);
    const DerivativeModel model = load_model(file);
    const Vehicle vehicle = load_vehicle(model.vehicle_file);
    const StateSpace ss = build_state_space(model, vehicle);
    const auto eig = sorted_eigenvalues(ss.A);
    REQUIRE(eig.size() == 3);
    CHECK(nearest_relative_error(eig, {pub.real_root, 0.0}) < 0.02);
    CHECK(nearest_relative_error(eig, {pub.osc_re, pub.osc_im}) < pub.tolerance);
    CHECK(nearest_relative_error(eig, {pub.osc_re, -pub.osc_im}) < pub.tolerance);
    const double radius = std::fabs(pub.real_root);  // the real root has the largest modulus
    CHECK(nearest_distance(eig, {pub.real_root, 0.0}) / radius < 0.02);
    CHECK(nearest_distance(eig, {pub.osc_re, pub.osc_im}) / radius < 0.02);
    CHECK(nearest_distance(eig, {pub.osc_re, -pub.osc_im}) / radius < 0.02);
  }
}

TEST_CASE("set 1 A and B entries follow the thesis equations (Eqs 10-17)", "[model]") {
  // Independent computation from thesis Table A.1, Table 9.2 and Eqs 10-17: vehicle without wifi module.
  const double m = 28.76e-3, Ixx = 9.60e-5, Izz = 3.32e-5, Ixz = -8.81e-6, g = 9.81;
  const double Ic = Ixx * Izz - Ixz * Ixz;
  const double Lp = -2.43e-4, Lv = -3.74e-4, Yp = 2.75e-3, Yv = -5.61e-2;
  const double Ldf = 1.06e-4, Ldt = 4.19e-5, Ydf = -8.63e-4, Ydt = -4.05e-4, w0 = -0.30;

  const DerivativeModel model = load_model(kConfigs + "models/nimble_lateral_set1.yaml");
  const Vehicle vehicle = load_vehicle(model.vehicle_file);
  const StateSpace ss = build_state_space(model, vehicle);
  REQUIRE(ss.states == std::vector<std::string>{"p", "v", "phi"});
  REQUIRE(ss.inputs == std::vector<std::string>{"delta_f", "delta_t"});

  const double tol = 1e-9;
  CHECK(ss.A(0, 0) == Approx(Izz / Ic * Lp).epsilon(tol));
  CHECK(ss.A(0, 1) == Approx(Izz / Ic * Lv).epsilon(tol));
  CHECK(ss.A(0, 2) == 0.0);
  CHECK(ss.A(1, 0) == Approx(Yp / m + w0).epsilon(tol));
  CHECK(ss.A(1, 1) == Approx(Yv / m).epsilon(tol));
  CHECK(ss.A(1, 2) == Approx(g).epsilon(tol));
  CHECK(ss.A(2, 0) == 1.0);
  CHECK(ss.A(2, 1) == 0.0);
  CHECK(ss.A(2, 2) == 0.0);
  CHECK(ss.B(0, 0) == Approx(Izz / Ic * Ldf).epsilon(tol));
  CHECK(ss.B(0, 1) == Approx(Izz / Ic * Ldt).epsilon(tol));
  CHECK(ss.B(1, 0) == Approx(Ydf / m).epsilon(tol));
  CHECK(ss.B(1, 1) == Approx(Ydt / m).epsilon(tol));
  CHECK(ss.B(2, 0) == 0.0);
  CHECK(ss.B(2, 1) == 0.0);
}

TEST_CASE("set 1 non-dimensional eigenvectors match thesis Table 6", "[model]") {
  const DerivativeModel model = load_model(kConfigs + "models/nimble_lateral_set1.yaml");
  const Vehicle vehicle = load_vehicle(model.vehicle_file);
  const auto modes = analyse_modes(build_state_space(model, vehicle), vehicle);
  REQUIRE(modes.size() == 2);

  // Mode 1: aperiodic, p 0.30 (180 deg), v 0.86 (180 deg), phi 1 (0 deg).
  // Mode 2: oscillatory, p 0.16 (83.4 deg), v 0.70 (-53.5 deg), phi 1 (0 deg).
  struct Expected {
    double mag, phase_deg;
  };
  const Expected table6[2][3] = {{{0.30, 180.0}, {0.86, 180.0}, {1.0, 0.0}}, {{0.16, 83.4}, {0.70, -53.5}, {1.0, 0.0}}};
  CHECK_FALSE(modes[0].oscillatory);
  CHECK(modes[1].oscillatory);
  for (int k = 0; k < 2; ++k) {
    for (int i = 0; i < 3; ++i) {
      INFO("mode " << k + 1 << " state " << i);
      const std::complex<double> c = modes[k].eigenvector_nondim[i];
      CHECK(std::abs(c) == Approx(table6[k][i].mag).margin(0.02));
      double dphase = std::arg(c) * 180.0 / M_PI - table6[k][i].phase_deg;
      dphase = std::remainder(dphase, 360.0);  // 180 and -180 deg are the same phase
      CHECK(std::fabs(dphase) < 2.0);
    }
  }
}

TEST_CASE("mode characteristics of set 1", "[model]") {
  const DerivativeModel model = load_model(kConfigs + "models/nimble_lateral_set1.yaml");
  const Vehicle vehicle = load_vehicle(model.vehicle_file);
  const auto modes = analyse_modes(build_state_space(model, vehicle), vehicle);
  REQUIRE(modes.size() == 2);
  const Mode& roll = modes[0];
  const Mode& osc = modes[1];
  CHECK(roll.stable);
  CHECK(roll.time_to_double_or_half_s == Approx(std::log(2.0) / -roll.eigenvalue.real()));
  CHECK_FALSE(osc.stable);
  CHECK(osc.natural_frequency_radps == Approx(std::abs(osc.eigenvalue)));
  CHECK(osc.damping_ratio == Approx(-osc.eigenvalue.real() / std::abs(osc.eigenvalue)));
  CHECK(osc.damping_ratio < 0.0);
  CHECK(osc.period_s == Approx(2.0 * M_PI / osc.eigenvalue.imag()));
  // Published 0.32 +- 2.73i: doubles in about 2.2 s, period about 2.3 s.
  CHECK(osc.time_to_double_or_half_s == Approx(2.17).epsilon(0.05));
  CHECK(osc.period_s == Approx(2.30).epsilon(0.05));
}

TEST_CASE("four-state model: decoupled and full roll-yaw inertia coupling", "[model]") {
  DerivativeModel model = load_model(kConfigs + "models/nimble_lateral4_yaw.yaml");
  const Vehicle v = load_vehicle(model.vehicle_file);
  REQUIRE(model.structure == Structure::kLateral4);
  REQUIRE(model.coupling == RollYawCoupling::kDecoupled);
  const double Ic = v.Ic();

  const StateSpace dec = build_state_space(model, v);
  REQUIRE(dec.states == std::vector<std::string>{"p", "r", "v", "phi"});
  CHECK(dec.A(0, 1) == Approx(v.Izz_kgm2 / Ic * -2.81e-4));
  CHECK(dec.A(1, 0) == Approx(v.Ixx_kgm2 / Ic * 5.55e-5));
  // The trim read from thesis Eq D.1 (A_grey): its v and phi rows to the printed precision.
  CHECK(dec.A(2, 0) == Approx(-0.156).margin(5e-4));  // Yp/m + w0
  CHECK(dec.A(2, 1) == Approx(-0.090).margin(5e-4));  // Yr/m - u0
  CHECK(dec.A(2, 1) == Approx(8.37e-3 / v.mass_kg - model.trim.u0_mps));
  CHECK(dec.A(2, 3) == Approx(9.743).margin(5e-4));  // g cos(theta0) cos(phi0)
  CHECK(dec.A(3, 0) == 1.0);
  CHECK(dec.A(3, 1) == Approx(-0.079).margin(5e-4));  // tan(theta0) cos(phi0)
  // With it, thesis Table 8.8: -8.44, 1.99 +- 5.54i, 2.70, each within 1 %.
  const Eigen::VectorXcd eig = dec.A.eigenvalues();
  for (const std::complex<double> published : {std::complex<double>(-8.44, 0), std::complex<double>(1.99, 5.54),
                                               std::complex<double>(1.99, -5.54), std::complex<double>(2.70, 0)}) {
    double nearest = 1e9;
    for (int i = 0; i < eig.size(); ++i) nearest = std::min(nearest, std::abs(eig(i) - published));
    INFO("Table 8.8 eigenvalue " << published);
    CHECK(nearest / std::abs(published) < 0.01);
  }

  model.coupling = RollYawCoupling::kFull;
  const StateSpace full = build_state_space(model, v);
  const double Lr = -2.81e-4, Nr = 1.01e-4, Ldw = 7.28e-3, Ndw = -7.09e-4;
  CHECK(full.A(0, 1) == Approx((v.Izz_kgm2 * Lr + v.Ixz_kgm2 * Nr) / Ic));
  CHECK(full.A(1, 1) == Approx((v.Ixz_kgm2 * Lr + v.Ixx_kgm2 * Nr) / Ic));
  // delta_w is the third input of the file.
  CHECK(full.B(0, 2) == Approx((v.Izz_kgm2 * Ldw + v.Ixz_kgm2 * Ndw) / Ic));
  CHECK(full.B(1, 2) == Approx((v.Ixz_kgm2 * Ldw + v.Ixx_kgm2 * Ndw) / Ic));
}

TEST_CASE("longitudinal model follows thesis Eq B.15", "[model]") {
  const DerivativeModel model = load_model(kConfigs + "models/nimble_longitudinal.yaml");
  const Vehicle v = load_vehicle(model.vehicle_file);
  const StateSpace ss = build_state_space(model, v);
  REQUIRE(ss.states == std::vector<std::string>{"q", "u", "w", "theta"});
  CHECK(ss.A(0, 0) == Approx(-1.90e-3 / v.Iyy_kgm2));
  CHECK(ss.A(1, 3) == Approx(-v.gravity_mps2));
  CHECK(ss.A(2, 3) == 0.0);
  CHECK(ss.A(3, 0) == 1.0);
  CHECK(ss.B(0, 0) == Approx(2.78e-1 / v.Iyy_kgm2));
  CHECK(ss.B(1, 0) == Approx(7.22e-1 / v.mass_kg));
}

TEST_CASE("exact ZOH discretisation matches a fine integration of the continuous model", "[model]") {
  const DerivativeModel model = load_model(kConfigs + "models/nimble_lateral_set1.yaml");
  const StateSpace ss = build_state_space(model, load_vehicle(model.vehicle_file));
  const double dt = 0.01;
  const DiscreteStateSpace d = discretize_zoh(ss, dt);

  Eigen::Vector3d x0(0.5, -0.1, 0.05);
  Eigen::Vector2d u(20.0, 3.0);
  // RK4 with 1000 sub-steps over one sample, input held constant.
  Eigen::Vector3d x = x0;
  const int n = 1000;
  const double h = dt / n;
  const auto f = [&](const Eigen::Vector3d& s) -> Eigen::Vector3d { return ss.A * s + ss.B * u; };
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d k1 = f(x), k2 = f(x + 0.5 * h * k1), k3 = f(x + 0.5 * h * k2), k4 = f(x + h * k3);
    x += h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
  }
  const Eigen::Vector3d xd = d.Ad * x0 + d.Bd * u;
  CHECK((xd - x).norm() < 1e-10 * (1.0 + x.norm()));

  // Discrete eigenvalues are exp(lambda dt).
  const auto ec = sorted_eigenvalues(ss.A);
  Eigen::EigenSolver<Eigen::MatrixXd> sd(d.Ad);
  for (const auto& lambda : ec) {
    const std::complex<double> z = std::exp(lambda * dt);
    double best = INFINITY;
    for (Eigen::Index i = 0; i < sd.eigenvalues().size(); ++i) best = std::min(best, std::abs(sd.eigenvalues()[i] - z));
    CHECK(best < 1e-10);
  }
  CHECK_THROWS_AS(discretize_zoh(ss, 0.0), std::invalid_argument);
}

TEST_CASE("a model file's terms: section is read, and a bad entry is refused naming file, line and key", "[model]") {
  std::ifstream in(kConfigs + "models/nimble_lateral_set1.yaml");
  std::string base((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto load = [&](const std::string& terms) {
    const std::string file = kConfigs + "models/terms_test.yaml";  // the relative vehicle path resolves
    ConfigMap map = ConfigMap::load_string(base + terms, file);
    return model_from_config(map);
  };
  const int line = static_cast<int>(std::count(base.begin(), base.end(), '\n')) + 2;  // the first entry
  const DerivativeModel m = load(
      "terms:\n  - {equation: L, expression: \"p^3\", coefficient: -2.0e-5}\n"
      "  - equation: Y\n    expression: lag(delta_f, 0.02)\n    coefficient: 1.5e-4\n");
  REQUIRE(m.terms.size() == 2);
  CHECK(m.terms[0].equation == "L");
  CHECK(m.terms[0].expression.to_string() == "p^3");
  CHECK(m.terms[0].coefficient == -2.0e-5);
  CHECK(m.terms[1].expression.stateful());
  CHECK(term_parameter_name(m.terms[1]) == "Y:lag(delta_f, 0.02)");

  const auto refused = [&](const std::string& terms) -> std::string {
    try {
      load(terms);
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "(accepted)";
  };
  const std::string where = kConfigs + "models/terms_test.yaml:" + std::to_string(line) + ": ";
  CHECK(refused("terms:\n  - {equation: L, expression: \"p^\", coefficient: 1}\n") ==
        where +
            "key 'terms[0].expression': value 'p^': does not parse: at position 3: expected an integer power in "
            "[0, 16] after '^', found the end");
  CHECK(refused("terms:\n  - {equation: L, expression: \"x*p\", coefficient: 1}\n") ==
        where +
            "key 'terms[0].expression': value 'x*p': reads an unknown signal 'x' (known: p, q, r, u, v, w, phi, "
            "theta, delta_f, delta_t, delta_d, delta_w)");
  CHECK(refused("terms:\n  - {equation: M, expression: \"p\", coefficient: 1}\n") ==
        where + "key 'terms[0].equation': value 'M': must be one of: L, Y");
  CHECK_THAT(refused("terms:\n  - {equation: L, expression: \"p\", coefficient: 1, gain: 2}\n"),
             Catch::Contains("terms[0].gain") && Catch::Contains(where));
  CHECK_THAT(refused("terms:\n  - {equation: L, expression: \"p\", coefficient: big}\n"),
             Catch::Contains("terms[0].coefficient") && Catch::Contains(where));
  CHECK_THAT(refused("terms:\n  - {equation: L, expression: \"p\"}\n"),
             Catch::Contains("terms[0].coefficient") && Catch::Contains("missing required key"));
  CHECK_THAT(refused("terms: p^3\n"), Catch::Contains("must be a list of terms"));
}
