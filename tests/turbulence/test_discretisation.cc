// Exact discretisation: ZOH and Van Loan; the stationary variance at any step; the
// white-noise intensity convention.

#include <cmath>
#include <random>

#include <catch2/catch.hpp>
#include <unsupported/Eigen/MatrixFunctions>

#include "test_support.h"
#include "turbulence/ce500_model.h"
#include "turbulence/discretisation.h"
#include "turbulence/dryden.h"
#include "turbulence/lyapunov.h"
#include "turbulence/spectral_estimates.h"
#include "turbulence/uncertainty.h"

using namespace nimble::turbulence;

TEST_CASE("Van Loan's covariance equals the defining integral of the process noise", "[turbulence][discretisation]") {
  Eigen::MatrixXd A(2, 2), G(2, 1), W(1, 1);
  A << 0.0, 1.0, -2.0, -0.7;
  G << 0.3, 1.1;
  W << 2.5;
  const double dt = 0.4;
  const Eigen::MatrixXd Q = van_loan_noise_covariance(A, G, W, dt);
  // Simpson on integral_0^dt exp(A s) G W G' exp(A' s) ds.
  const int n = 2000;
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(2, 2);
  for (int i = 0; i <= n; ++i) {
    const double s = dt * i / n;
    const Eigen::MatrixXd E = (A * s).exp();
    const double weight = (i == 0 || i == n) ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
    sum += weight * E * G * W * G.transpose() * E.transpose();
  }
  const Eigen::MatrixXd expected = sum * dt / (3.0 * n);
  CHECK((Q - expected).norm() < 1e-10 * expected.norm());
}

TEST_CASE("ZOH of a deterministic input is the integrated matrix exponential", "[turbulence][discretisation]") {
  LinearSystem s;
  s.A = Eigen::MatrixXd::Constant(1, 1, -0.8);
  s.B = Eigen::MatrixXd::Constant(1, 1, 2.0);
  s.C = Eigen::MatrixXd::Constant(1, 1, 1.0);
  s.D = Eigen::MatrixXd::Zero(1, 1);
  const DiscreteModel d = discretise(s, Eigen::VectorXd::Zero(1), 0.3);
  CHECK(d.Phi(0, 0) == Approx(std::exp(-0.8 * 0.3)).epsilon(1e-14));
  CHECK(d.Gamma(0, 0) == Approx((1.0 - std::exp(-0.8 * 0.3)) / 0.8 * 2.0).epsilon(1e-13));
  CHECK(d.Qd.norm() == 0.0);  // no driven noise input
}

TEST_CASE("Exact discretisation keeps the continuous stationary variance at coarse and fine steps",
          "[turbulence][discretisation]") {
  const auto& config = nimble::turbulence::test::practical();
  const LinearSystem ce500 = ce500_controlled_model(config);
  const Eigen::VectorXd W_ce500 = ce500_noise_intensity(config);
  const ShapingFilter filter = dryden_lateral(1.0, 150.0, 51.4);
  const Eigen::VectorXd W1 = Eigen::VectorXd::Ones(1);
  struct Case {
    const LinearSystem* sys;
    const Eigen::VectorXd* W;
  };
  for (const Case c : {Case{&filter.system, &W1}, Case{&ce500, &W_ce500}}) {
    const Eigen::MatrixXd P = stationary_covariance(*c.sys, *c.W);
    const Eigen::VectorXd exact = output_variances(*c.sys, *c.W, P);
    for (const double dt : {0.001, 0.05, 0.5, 2.0}) {
      INFO("dt " << dt);
      const DiscreteModel d = discretise(*c.sys, *c.W, dt);
      const Eigen::MatrixXd Pd = solve_discrete_lyapunov(d.Phi, d.Qd);
      const Eigen::VectorXd discrete = (c.sys->C * Pd * c.sys->C.transpose()).diagonal();
      CHECK((discrete - exact).cwiseAbs().maxCoeff() <= 1e-9 * exact.maxCoeff());
    }
    // The practical's held noise (randn/sqrt(dt) over each step) does not keep it at a coarse step.
    const DiscreteModel coarse = discretise(*c.sys, *c.W, 1.0);
    const Eigen::MatrixXd Ph = solve_discrete_lyapunov(coarse.Phi, held_noise_covariance(coarse, *c.W));
    const Eigen::VectorXd held = (c.sys->C * Ph * c.sys->C.transpose()).diagonal();
    CHECK((held.array() / exact.array() - 1.0).abs().maxCoeff() > 0.01);
  }
}

TEST_CASE("Unit intensity means held samples of variance 1 over dt and a simulated variance of sigma^2",
          "[turbulence][discretisation]") {
  const double sigma = 2.0, T = 1.0;
  const ShapingFilter f = time_based_first_order(sigma, T);
  const Eigen::VectorXd W = Eigen::VectorXd::Ones(1);
  const Eigen::MatrixXd P = stationary_covariance(f.system, W);
  REQUIRE(P(0, 0) == Approx(sigma * sigma).epsilon(1e-12));

  // Exact discretisation at a coarse step (dt = T): the record's sample variance is sigma^2
  // within its stated uncertainty.
  const double dt = 1.0;
  const std::size_t N = 100000;
  const DiscreteModel d = discretise(f.system, W, dt);
  const Eigen::VectorXd x = simulate_stationary(d, P, N, 7).col(0);
  const double sd =
      quadratic_estimate_std(sample_variance_weights(N), sampled_autocovariance(d.Phi, P, f.system.C.row(0), N));
  CHECK(std::abs(sample_variance(x) - sigma * sigma) < 4.0 * sd);

  // The same intensity as held samples w_k = n_k / sqrt(dt) at a fine step (Euler-like):
  // x_{k+1} = Phi x_k + Gamma w_k has the variance sigma^2 (1 + O(dt / T)).
  const double fine = 0.001;
  const DiscreteModel h = discretise(f.system, W, fine);
  const Eigen::MatrixXd Ph = solve_discrete_lyapunov(h.Phi, held_noise_covariance(h, W));
  CHECK(Ph(0, 0) == Approx(sigma * sigma).epsilon(2e-3));
  // ... and a wrong convention (samples of variance 1, not 1/dt) misses it by the factor dt.
  CHECK(Ph(0, 0) * fine < 0.01 * sigma * sigma);
}
