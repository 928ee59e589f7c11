// The hover closed loop in Dryden gusts (turbulence/hover_gust_response.h), the expected
// Welch estimate and the binomial bound it uses.

#include <cmath>
#include <map>
#include <string>

#include <catch2/catch.hpp>

#include "core/model.h"
#include "core/vehicle.h"
#include "turbulence/discretisation.h"
#include "turbulence/dryden.h"
#include "turbulence/hover_gust_response.h"
#include "turbulence/lyapunov.h"
#include "turbulence/spectral_density.h"
#include "turbulence/spectral_estimates.h"
#include "turbulence/uncertainty.h"

using namespace nimble::turbulence;

namespace {

struct Set1 {
  nimble::DerivativeModel model =
      nimble::load_model(std::string(RIG_SOURCE_DIR) + "/rig_configs/models/nimble_lateral_set1.yaml");
  nimble::Vehicle vehicle = nimble::load_vehicle(model.vehicle_file);
};

/// p, v, phi of a stationary record of `loop` at dt.
std::map<std::string, Eigen::VectorXd> simulate(const LinearSystem& loop, double dt, std::size_t N,
                                                std::uint64_t seed) {
  const Eigen::VectorXd W = Eigen::VectorXd::Ones(1);
  const DiscreteModel d = discretise(loop, W, dt);
  const Eigen::MatrixXd X = simulate_stationary(d, stationary_covariance(loop, W), N, seed);
  const Eigen::MatrixXd Y = X * loop.C.transpose();
  return {{"p", Y.col(0)}, {"v", Y.col(1)}, {"phi", Y.col(2)}};
}

}  // namespace

TEST_CASE("Binomial upper quantile: the smallest count with the cumulative probability", "[turbulence][hover]") {
  CHECK(binomial_upper_quantile(20, 0.05, 0.95) == 3);  // P(X <= 2) = 0.9245, P(X <= 3) = 0.9841
  CHECK(binomial_upper_quantile(20, 0.05, 0.90) == 2);
  CHECK(binomial_upper_quantile(10, 0.0, 0.999) == 0);
  CHECK(binomial_upper_quantile(10, 1.0, 0.5) == 10);
  CHECK(binomial_upper_quantile(0, 0.05, 0.999) == 0);
  CHECK_THROWS(binomial_upper_quantile(10, 0.05, 1.0));
}

TEST_CASE("Expected Welch estimate: integrates to R_0 and is the sampled PSD where it is smooth",
          "[turbulence][hover]") {
  const ShapingFilter f = time_based_second_order(0.3, 2.0);
  const Eigen::VectorXd W = Eigen::VectorXd::Ones(1);
  const double dt = 0.01;
  const DiscreteModel d = discretise(f.system, W, dt);
  const Eigen::MatrixXd P = stationary_covariance(f.system, W);
  const Eigen::RowVectorXd c = f.system.C.row(0);
  const std::size_t M = 4096;
  const Eigen::VectorXd R = sampled_autocovariance(d.Phi, P, c, 100000, 1e-12);
  const Eigen::VectorXd E = welch_expectation(R, dt, M, M / 2 + 1);
  SpectralEstimate e;
  e.psd = E;
  e.d_omega_radps = 2.0 * M_PI / (static_cast<double>(M) * dt);
  CHECK(variance_from_estimate(e) == Approx(R[0]).epsilon(1e-9));
  const Eigen::VectorXd omega =
      Eigen::VectorXd::LinSpaced(E.size(), 0.0, e.d_omega_radps * static_cast<double>(E.size() - 1));
  const Eigen::MatrixXd S = sampled_output_psd(d.Phi, P, f.system.C, dt, omega);
  for (const Eigen::Index k : {20, 100, 1000}) CHECK(E[k] == Approx(S(k, 0)).epsilon(0.01));
  CHECK_THROWS(welch_expectation(R, dt, 1000, 10));
  CHECK_THROWS(welch_expectation(R, dt, M, M));
}

TEST_CASE("Hover gust loop: set 1 with the fast gains is stable and carries the plant's gust", "[turbulence][hover]") {
  const Set1 s;
  HoverLoopParameters params;
  params.gust_sigma_mps = 0.2;
  params.gust_time_scale_s = 1.5;
  const LinearSystem loop = hover_gust_loop(s.model, s.vehicle, params);
  for (const auto& z : eigenvalues(loop.A)) CHECK(z.real() < -0.1);
  const Eigen::VectorXd W = Eigen::VectorXd::Ones(1);
  const Eigen::VectorXd var = output_variances(loop, W, stationary_covariance(loop, W));
  CHECK(var[index_of(loop.outputs, "v_g")] == Approx(0.04).epsilon(1e-9));
  // Without gains the aircraft block is the open-loop model (thesis Table 9.5 eigenvalues).
  HoverLoopParameters open = params;
  open.kp_per_rad = 0.0;
  open.kd_per_radps = 0.0;
  const Eigen::MatrixXd A = hover_gust_loop(s.model, s.vehicle, open).A.topLeftCorner(3, 3);
  const auto z = eigenvalues(A);
  CHECK(z[0].real() == Approx(0.32).margin(0.02));
  CHECK(std::abs(z[0].imag()) == Approx(2.73).margin(0.03));
  // A steady side wind is followed by the side velocity: v / v_g -> 1 at omega -> 0.
  const Eigen::MatrixXcd H0 = frequency_response(loop, 1e-6);
  CHECK(std::abs(H0(1, 0) / H0(3, 0)) == Approx(1.0).epsilon(1e-4));
  CHECK_THROWS(hover_gust_loop(s.model, s.vehicle, HoverLoopParameters{1.0, 0.2, 15.0, 125.0, 8.97, 12.56, 0.0, 1.0}));
}

TEST_CASE("Hover response comparison: a record of the loop agrees, one with another sigma does not",
          "[turbulence][hover]") {
  const Set1 s;
  HoverLoopParameters params;
  const LinearSystem loop = hover_gust_loop(s.model, s.vehicle, params);
  const double dt = 1e-3;
  ResponseComparisonOptions options;
  options.welch_segment = 8192;
  for (const std::uint64_t seed : {1u, 2u}) {
    INFO("seed " << seed);
    const ResponseComparison c = compare_hover_response(loop, simulate(loop, dt, 55000, seed), dt, options);
    for (const auto& o : c.outputs) {
      INFO(o.name << ": outside " << o.outside << " of " << o.counted << " (allowed " << o.allowed << "), mean ratio "
                  << o.mean_ratio << " +- " << o.mean_ratio_sigma << ", variance " << o.flight_variance << " against "
                  << o.model_variance << " +- " << o.flight_variance_sigma);
      CHECK(o.bins_agree);
      CHECK(o.mean_agrees);
      CHECK(o.variance_agrees);
      CHECK(o.max_analytical_deviation < 0.25);  // leakage at the lowest bins of v
    }
    CHECK(c.agrees());
  }
  HoverLoopParameters stronger = params;
  stronger.gust_sigma_mps = 2.0 * params.gust_sigma_mps;
  const ResponseComparison wrong =
      compare_hover_response(loop, simulate(hover_gust_loop(s.model, s.vehicle, stronger), dt, 55000, 1), dt, options);
  CHECK_FALSE(wrong.agrees());
  for (const auto& o : wrong.outputs) CHECK_FALSE(o.mean_agrees);
}
