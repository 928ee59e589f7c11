// Dryden shaping filters: state space, analytical PSD and variance agree; the standards' forms;
// a simulated record's Welch PSD inside the confidence band.

#include <cmath>
#include <vector>

#include <catch2/catch.hpp>

#include "turbulence/discretisation.h"
#include "turbulence/dryden.h"
#include "turbulence/lyapunov.h"
#include "turbulence/spectral_density.h"
#include "turbulence/spectral_estimates.h"
#include "turbulence/uncertainty.h"

using namespace nimble::turbulence;

namespace {

constexpr double kV = 51.4;
constexpr double kL = 150.0;

std::vector<ShapingFilter> all_filters() {
  return {
      time_based_first_order(0.7, 2.0),
      time_based_second_order(0.7, 2.0),
      dryden_longitudinal(1.2, kL, kV),
      dryden_lateral(1.2, kL, kV),
      dryden_vertical(1.2, kL, kV),
      dryden_lateral(1.2, kL, kV, DrydenStandard::kMilHdbk1797),
      dryden_vertical(1.2, kL, kV, DrydenStandard::kMilHdbk1797),
      practical_filter("u_g", practical_asymmetric_coefficients(kV, kL, 0.0991, 0.5545, 0.4159, 0.0249 / (kV * kV))),
      practical_filter("alpha_g", practical_asymmetric_coefficients(kV, kL, 0.06, 0.3294, 0.2243, 0.0182 / (kV * kV))),
      practical_filter("beta_g", practical_beta_g_coefficients(1.0, kV, kL))};
}

}  // namespace

TEST_CASE("Each Dryden filter's state space has its analytical PSD and its variance", "[turbulence][dryden]") {
  const Eigen::VectorXd W = Eigen::VectorXd::Ones(1);
  for (const auto& f : all_filters()) {
    INFO(f.name);
    for (const double w : {0.0, 0.01, 0.3, 1.0, 3.0, 30.0}) {
      const double S = output_psd(f.system, W, w)[0];
      CHECK(S == Approx(f.psd(w)).epsilon(1e-10));
    }
    const double lyap = output_variances(f.system, W, stationary_covariance(f.system, W))[0];
    CHECK(lyap == Approx(f.variance).epsilon(1e-10));
    CHECK(integrate_psd(f.psd).value == Approx(f.variance).epsilon(1e-7));
  }
}

TEST_CASE("Standard Dryden forms have variance sigma^2 and the published spatial PSDs", "[turbulence][dryden]") {
  const double sigma = 1.3;
  const auto spatial = [](double Omega_radpm, double L, double s, bool lateral_1797, bool lateral) {
    const double x = L * Omega_radpm;
    if (!lateral) return s * s * (2.0 * L / M_PI) / (1.0 + x * x);
    if (lateral_1797) return s * s * (2.0 * L / M_PI) * (1.0 + 12.0 * x * x) / std::pow(1.0 + 4.0 * x * x, 2.0);
    return s * s * (L / M_PI) * (1.0 + 3.0 * x * x) / std::pow(1.0 + x * x, 2.0);
  };
  const ShapingFilter u = dryden_longitudinal(sigma, kL, kV);
  const ShapingFilter v = dryden_lateral(sigma, kL, kV);
  const ShapingFilter w1797 = dryden_vertical(sigma, kL, kV, DrydenStandard::kMilHdbk1797);
  for (const auto* f : {&u, &v, &w1797}) CHECK(f->variance == Approx(sigma * sigma).epsilon(1e-12));
  for (const double w : {0.01, 0.2, 1.0, 5.0}) {
    // S(omega) = (pi / V) Phi(omega / V): the library's convention from the spatial one.
    CHECK(u.psd(w) == Approx(M_PI / kV * spatial(w / kV, kL, sigma, false, false)).epsilon(1e-12));
    CHECK(v.psd(w) == Approx(M_PI / kV * spatial(w / kV, kL, sigma, false, true)).epsilon(1e-12));
    CHECK(w1797.psd(w) == Approx(M_PI / kV * spatial(w / kV, kL, sigma, true, true)).epsilon(1e-12));
  }
}

TEST_CASE("The practical's beta_g filter is the MIL-F-8785C lateral form of sigma over V", "[turbulence][dryden]") {
  const ShapingFilter bg = practical_filter("beta_g", practical_beta_g_coefficients(1.0, kV, kL));
  const ShapingFilter v = dryden_lateral(1.0 / kV, kL, kV);
  for (const double w : {0.0, 0.05, 0.34, 2.0, 20.0}) CHECK(bg.psd(w) == Approx(v.psd(w)).epsilon(1e-12));
  CHECK(bg.variance == Approx(1.0 / (kV * kV)).epsilon(1e-12));
}

TEST_CASE("Dryden filter Welch PSD of a long seeded record lies inside the analytical confidence band",
          "[turbulence][dryden]") {
  const ShapingFilter f = dryden_lateral(1.5, kL, kV);
  const double dt = 0.05;
  const Eigen::VectorXd W = Eigen::VectorXd::Ones(1);
  const DiscreteModel d = discretise(f.system, W, dt);
  const Eigen::MatrixXd P = stationary_covariance(f.system, W);
  const std::size_t N = 1 << 18;
  const Eigen::VectorXd x = (simulate_stationary(d, P, N, 42) * f.system.C.transpose()).col(0);
  const SpectralEstimate e = welch(x, dt, 1024);
  REQUIRE(e.segments == 511);
  // The sampled process's exact PSD (aliasing included) is what the estimate estimates.
  const Eigen::MatrixXd S = sampled_output_psd(d.Phi, P, f.system.C, dt, e.omega_radps);
  const ConfidenceBand b95 = psd_confidence_band(e.dof, 0.95);
  const ConfidenceBand b_wide = psd_confidence_band(e.dof, 0.99999);
  int outside95 = 0, outside_wide = 0, bins = 0;
  for (Eigen::Index k = 2; k + 1 < e.psd.size(); ++k) {  // interior bins; bin 1 sits on the mean removal
    const double r = e.psd[k] / S(k, 0);
    outside95 += (r < b95.lower || r > b95.upper) ? 1 : 0;
    outside_wide += (r < b_wide.lower || r > b_wide.upper) ? 1 : 0;
    ++bins;
  }
  INFO("bins " << bins << ", outside 95 %: " << outside95 << ", dof " << e.dof);
  CHECK(outside95 <= 0.10 * bins);
  CHECK(outside_wide == 0);
  // Far below Nyquist the sampled PSD is the analytical one.
  CHECK(S(10, 0) == Approx(f.psd(e.omega_radps[10])).epsilon(1e-3));
}
