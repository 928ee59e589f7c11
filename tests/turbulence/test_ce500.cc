// The Ce500 model of the practical: Table 2.1, the construction, the reduced model and the
// reasons given for Table 5.1.

#include <cmath>
#include <complex>
#include <string>

#include <catch2/catch.hpp>

#include "test_support.h"
#include "turbulence/ce500_analysis.h"
#include "turbulence/ce500_model.h"

using namespace nimble::turbulence;

namespace {

/// The mode name of our eigenvalue nearest to z.
std::string mode_at(const std::vector<NamedEigenvalue>& eig, std::complex<double> z) {
  double best = INFINITY;
  std::string name;
  for (const auto& e : eig) {
    if (std::abs(e.value - z) < best) {
      best = std::abs(e.value - z);
      name = e.mode;
    }
  }
  return name;
}

}  // namespace

TEST_CASE("Table 2.1: uncontrolled, controlled and reduced eigenvalues within 1e-3", "[turbulence][ce500]") {
  const auto& c = nimble::turbulence::test::practical();
  const auto uncontrolled = ce500_named_eigenvalues(ce500_full_model(c));
  const auto controlled = ce500_named_eigenvalues(ce500_controlled_model(c));
  const auto reduced = ce500_named_eigenvalues(ce500_reduced_model(c));
  for (const auto& [ours, published] :
       {std::make_pair(&uncontrolled, &c.published.uncontrolled), std::make_pair(&controlled, &c.published.controlled),
        std::make_pair(&reduced, &c.published.reduced)}) {
    for (const auto& m : match_eigenvalues(*ours, *published)) {
      INFO("ours " << m.ours.value << ", published " << m.published);
      CHECK(m.distance < 1e-3);
    }
  }
  CHECK(mode_at(uncontrolled, {-0.1826, 1.6032}) == "Dutch roll");
  CHECK(mode_at(uncontrolled, {0.0763, 0.0}) == "spiral (unstable)");
  CHECK(mode_at(uncontrolled, {-1.7462, 0.0}) == "aperiodic roll");
  CHECK(mode_at(uncontrolled, {-5.7111, 0.0}) == "alpha_g filter (gust pole)");
  CHECK(mode_at(controlled, {-0.4799, 0.0}) == "spiral");
  CHECK(mode_at(controlled, {-1.1605, 0.0}) == "aperiodic roll");
  CHECK(mode_at(reduced, {-0.1523, 1.5484}) == "Dutch roll");
  CHECK(mode_at(reduced, {-0.7920, -0.3623}).rfind("roll pair", 0) == 0);
  CHECK(mode_at(reduced, {-0.3427, 0.0}) == "beta_g filter (gust pole)");
}

TEST_CASE("The construction gives the practical's B entries and the corrected gust entries", "[turbulence][ce500]") {
  const Ce500Coefficients k = ce500_coefficients(nimble::turbulence::test::practical());
  CHECK(k.y_dr == Approx(0.0449).margin(5e-5));
  CHECK(k.l_da == Approx(-1.0864).margin(5e-5));
  CHECK(k.l_dr == Approx(0.1037).margin(5e-5));
  CHECK(k.n_da == Approx(-0.0014).margin(5e-5));
  CHECK(k.n_dr == Approx(-0.2281).margin(5e-5));
  CHECK(k.u_g.b1 == Approx(0.0136).margin(5e-5));
  CHECK(k.u_g.b2 == Approx(-0.0442).margin(5e-5));
  CHECK(k.alpha_g.b1 == Approx(0.0174).margin(5e-5));
  CHECK(k.alpha_g.b2 == Approx(-0.0911).margin(5e-5));  // paper-facts: not the printed -0.0996
  CHECK(k.beta_g.b1 == Approx(0.0197).margin(5e-5));
  CHECK(k.beta_g.b2 == Approx(-0.0096).margin(5e-5));
}

TEST_CASE("The reduced model's moment rows carry the full model's gust columns", "[turbulence][ce500]") {
  Ce500Config c = nimble::turbulence::test::practical();
  const LinearSystem full = ce500_full_model(c);
  c.reduced_gust_columns = ReducedGustColumns::kMomentRows;
  const LinearSystem moments = ce500_reduced_model(c, false);
  c.reduced_gust_columns = ReducedGustColumns::kFullModelRows;
  const LinearSystem rows = ce500_reduced_model(c, false);
  CHECK((moments.A.block(2, 4, 2, 6) - full.A.block(2, 4, 2, 6)).norm() < 1e-12);
  CHECK(moments.A.block(0, 4, 1, 6).norm() == 0.0);
  CHECK((rows.A.block(0, 4, 4, 6) - full.A.block(0, 4, 4, 6)).norm() < 1e-12);
  // beta = -psi: beta_dot = -r = -(2V/b) rb/2V, phi_dot = (2V/b) pb/2V.
  const double two_v_over_b = 2.0 * c.flight.V_mps / c.flight.b_m;
  CHECK(rows.A(0, 3) == Approx(-two_v_over_b).epsilon(1e-12));
  CHECK(rows.A(1, 2) == Approx(two_v_over_b).epsilon(1e-12));
  CHECK(rows.A.block(0, 0, 1, 3).norm() == 0.0);
}

TEST_CASE("The lateral acceleration output is V (beta_dot + r) of the side-force equation", "[turbulence][ce500]") {
  const auto& c = nimble::turbulence::test::practical();
  const LinearSystem s = ce500_controlled_model(c);
  const double V = c.flight.V_mps;
  Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(10, 0.1, 1.0);
  const double beta_dot = s.A.row(0).dot(x);
  const double r = x[3] * 2.0 * V / c.flight.b_m;
  CHECK((s.C * x)[4] == Approx(V * (beta_dot + r)).epsilon(1e-12));
  CHECK((s.C * x)[0] == Approx(x[0] * 180.0 / M_PI).epsilon(1e-12));
  // No feedthrough from the gust noise: a finite variance.
  CHECK(s.D.rightCols(3).norm() == 0.0);
}

TEST_CASE("Table 5.1 reasons: the practical's fft is twice its var.m and its rate rows are in rad/s",
          "[turbulence][ce500]") {
  Ce500Options o = ce500_default_options(nimble::turbulence::test::practical());
  o.duration_s = 300.0;
  const Ce500Analysis a = analyse_ce500(nimble::turbulence::test::practical(), o);
  REQUIRE(a.table_5_1.size() == 5 * 2 * 4);
  int fft_factor2 = 0, rate_units = 0;
  for (const auto& cell : a.table_5_1) {
    if (cell.method == "fft" && cell.explained && cell.explanation_name.find("factor 2") != std::string::npos) {
      ++fft_factor2;
    }
    if ((cell.output == "p_hat" || cell.output == "r_hat") && cell.method == "analytical" && cell.explained &&
        cell.reason.find("rad/s") != std::string::npos) {
      ++rate_units;
    }
  }
  CHECK(fft_factor2 == 10);
  CHECK(rate_units == 4);
  for (const auto& col : a.table_2_1) CHECK(col.max_distance < 1e-3);
}
