// Lyapunov solutions, MIMO PSDs summed in power, and the variance from the analytical PSD.

#include <cmath>
#include <string>

#include <catch2/catch.hpp>
#include <unsupported/Eigen/MatrixFunctions>

#include "test_support.h"
#include "turbulence/ce500_model.h"
#include "turbulence/lyapunov.h"
#include "turbulence/spectral_density.h"

using namespace nimble::turbulence;

TEST_CASE("Continuous and discrete Lyapunov solutions satisfy their equations", "[turbulence][lyapunov]") {
  Eigen::MatrixXd A(3, 3);
  A << -1.0, 2.0, 0.0, -2.0, -0.5, 1.0, 0.3, 0.0, -3.0;
  Eigen::MatrixXd G(3, 2);
  G << 1.0, 0.0, 0.5, 1.0, 0.0, 2.0;
  const Eigen::MatrixXd Q = G * G.transpose();
  const Eigen::MatrixXd P = solve_continuous_lyapunov(A, Q);
  CHECK((A * P + P * A.transpose() + Q).norm() < 1e-12 * Q.norm());
  CHECK((P - P.transpose()).norm() == 0.0);
  // Scalar closed form: P = q / (-2 a).
  CHECK(solve_continuous_lyapunov(Eigen::MatrixXd::Constant(1, 1, -0.25), Eigen::MatrixXd::Constant(1, 1, 3.0))(0, 0) ==
        Approx(6.0).epsilon(1e-14));
  const Eigen::MatrixXd Phi = (0.3 * A).exp();
  const Eigen::MatrixXd Pd = solve_discrete_lyapunov(Phi, Q);
  CHECK((Phi * Pd * Phi.transpose() + Q - Pd).norm() < 1e-12 * Pd.norm());
}

TEST_CASE("Lyapunov refuses the unstable uncontrolled Ce500 and names the spiral eigenvalue",
          "[turbulence][lyapunov]") {
  const auto& config = nimble::turbulence::test::practical();
  const LinearSystem open = ce500_full_model(config);
  try {
    stationary_covariance(open, ce500_noise_intensity(config));
    FAIL("expected an error for the unstable spiral");
  } catch (const std::invalid_argument& e) {
    CHECK(std::string(e.what()).find("0.0763") != std::string::npos);
  }
}

TEST_CASE("Lyapunov variances equal the integral of the analytical PSD within 1 %", "[turbulence][lyapunov]") {
  const auto& config = nimble::turbulence::test::practical();
  const Eigen::VectorXd W = ce500_noise_intensity(config);
  for (const LinearSystem& s : {ce500_controlled_model(config), ce500_reduced_model(config)}) {
    const Eigen::VectorXd lyap = output_variances(s, W, stationary_covariance(s, W));
    const VectorQuadrature q = integrate_psds([&](double w) -> Eigen::VectorXd { return output_psd(s, W, w); });
    for (Eigen::Index i = 0; i < lyap.size(); ++i) {
      INFO(s.outputs[static_cast<std::size_t>(i)]);
      CHECK(std::abs(q.value[i] / lyap[i] - 1.0) < 0.01);
      CHECK(std::abs(q.value[i] / lyap[i] - 1.0) < 1e-7);  // in fact to the quadrature's accuracy
      CHECK(q.error[i] < 1e-8 * lyap[i]);
    }
  }
}

TEST_CASE("Independent inputs add in power, not in amplitude", "[turbulence][lyapunov]") {
  const auto& config = nimble::turbulence::test::practical();
  const LinearSystem s = ce500_controlled_model(config);
  const Eigen::VectorXd W = ce500_noise_intensity(config);
  Eigen::VectorXd W_v = W, W_w = W;
  W_v[3] = 0.0;  // v_g only (w2)
  W_w[4] = 0.0;  // w_g only (w3)
  REQUIRE(W_v.sum() > 0.0);
  REQUIRE(W_w.sum() > 0.0);
  const Eigen::VectorXd both = output_variances(s, W, stationary_covariance(s, W));
  const Eigen::VectorXd v_only = output_variances(s, W_v, stationary_covariance(s, W_v));
  const Eigen::VectorXd w_only = output_variances(s, W_w, stationary_covariance(s, W_w));
  CHECK((both - v_only - w_only).cwiseAbs().maxCoeff() < 1e-12 * both.maxCoeff());
  for (const double w : {0.1, 1.6, 10.0}) {
    const Eigen::VectorXd S = output_psd(s, W, w);
    const Eigen::VectorXd sum = output_psd(s, W_v, w) + output_psd(s, W_w, w);
    CHECK((S - sum).cwiseAbs().maxCoeff() < 1e-12 * S.maxCoeff());
    // The coherent sum (|H1| + |H2|)^2 is larger wherever both inputs reach an output.
    const Eigen::VectorXd coherent = coherent_output_psd(s, W, w);
    CHECK(coherent[1] > 1.01 * S[1]);
  }
}
