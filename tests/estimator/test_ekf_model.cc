// Unit tests of the EKF process and measurement model (estimator/ekf_model.h): analytic Jacobians
// against central differences at random states (GTSAM-style), the discrete step, and the
// covariance propagation of AttitudeVelocityEkf against the documented 12x12 formula.

#include <cmath>
#include <functional>
#include <random>

#include <catch2/catch.hpp>

#include "core/attitude.h"
#include "estimator/ekf.h"
#include "estimator/ekf_model.h"

using namespace nimble;

namespace {

/// Central-difference Jacobian of fn at x (columns: d fn / d x_i).
template <int N>
Eigen::MatrixXd numerical_jacobian(const std::function<Eigen::VectorXd(const Eigen::Matrix<double, N, 1>&)>& fn,
                                   const Eigen::Matrix<double, N, 1>& x, double h = 1e-6) {
  const Eigen::VectorXd f0 = fn(x);
  Eigen::MatrixXd J(f0.size(), N);
  for (int i = 0; i < N; ++i) {
    Eigen::Matrix<double, N, 1> xp = x, xm = x;
    xp[i] += h;
    xm[i] -= h;
    J.col(i) = (fn(xp) - fn(xm)) / (2.0 * h);
  }
  return J;
}

/// Random state away from the pitch singularity and the +-pi wrap of phi and psi.
EkfState random_state(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  EkfState x;
  x << 2.5 * u(rng), 1.2 * u(rng), 2.5 * u(rng),  // phi theta psi [rad]
      1.5 * u(rng), 1.5 * u(rng), 1.0 * u(rng),   // u v w [m/s]
      0.1 * u(rng), 0.1 * u(rng), 0.1 * u(rng),   // gyro bias [rad/s]
      0.5 * u(rng), 0.5 * u(rng), 0.5 * u(rng);   // accel bias [m/s^2]
  return x;
}

EkfInput random_input(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  EkfInput in;
  in << 10.0 * u(rng), 5.0 * u(rng), 5.0 * u(rng), 3.0 * u(rng), 3.0 * u(rng), -9.81 + 3.0 * u(rng);
  return in;
}

double relative_error(const Eigen::MatrixXd& analytic, const Eigen::MatrixXd& numeric) {
  return (analytic - numeric).cwiseAbs().maxCoeff() / std::max(1.0, numeric.cwiseAbs().maxCoeff());
}

}  // namespace

TEST_CASE("process Jacobian F = df/dx matches central differences at random states", "[ekf_model]") {
  std::mt19937_64 rng(11);
  const EkfModelParams params;
  double worst = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    const EkfState x = random_state(rng);
    const EkfInput u = random_input(rng);
    const std::function<Eigen::VectorXd(const EkfState&)> f = [&](const EkfState& xx) {
      return Eigen::VectorXd(ekf_process_derivative(xx, u, params));
    };
    const double err = relative_error(ekf_process_jacobian(x, u, params), numerical_jacobian<12>(f, x));
    worst = std::max(worst, err);
  }
  INFO("largest relative difference " << worst);
  CHECK(worst < 1e-6);
}

TEST_CASE("input Jacobian G = df/du_m matches central differences", "[ekf_model]") {
  std::mt19937_64 rng(12);
  const EkfModelParams params;
  double worst = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    const EkfState x = random_state(rng);
    const EkfInput u = random_input(rng);
    const std::function<Eigen::VectorXd(const EkfInput&)> f = [&](const EkfInput& uu) {
      return Eigen::VectorXd(ekf_process_derivative(x, uu, params));
    };
    worst = std::max(worst, relative_error(ekf_input_jacobian(x, u, params), numerical_jacobian<6>(f, u)));
  }
  CHECK(worst < 1e-6);
}

TEST_CASE("Jacobian of the discrete Heun step matches central differences", "[ekf_model]") {
  std::mt19937_64 rng(13);
  const EkfModelParams params;
  double worst = 0.0;
  for (int trial = 0; trial < 100; ++trial) {
    const EkfState x = random_state(rng);
    const EkfInput u0 = random_input(rng);
    const EkfInput u1 = u0 + 0.1 * random_input(rng);
    for (const double dt : {1.0 / 512.0, 0.01}) {
      const std::function<Eigen::VectorXd(const EkfState&)> step = [&](const EkfState& xx) {
        return Eigen::VectorXd(ekf_discrete_step(xx, u0, u1, dt, params));
      };
      worst = std::max(worst,
                       relative_error(ekf_discrete_jacobian(x, u0, u1, dt, params), numerical_jacobian<12>(step, x)));
    }
  }
  CHECK(worst < 1e-7);
}

TEST_CASE("measurement Jacobian H matches central differences", "[ekf_model]") {
  std::mt19937_64 rng(14);
  for (const int dim : {3, 6}) {
    const EkfState x = random_state(rng);
    const std::function<Eigen::VectorXd(const EkfState&)> h = [&](const EkfState& xx) {
      return ekf_measurement(xx, dim);
    };
    CHECK(relative_error(ekf_measurement_jacobian(x, dim), numerical_jacobian<12>(h, x)) < 1e-9);
  }
}

TEST_CASE("process model: specific-force convention and kinematics", "[ekf_model]") {
  const EkfModelParams params;
  SECTION("at rest and level the accelerometer reads (0, 0, -g) and nothing moves") {
    EkfInput u;
    u << 0, 0, 0, 0, 0, -9.81;
    CHECK(ekf_process_derivative(EkfState::Zero(), u, params).norm() < 1e-12);
  }
  SECTION("hovering at a roll angle with vertical thrust only: the body accelerates sideways") {
    EkfState x = EkfState::Zero();
    x[kPhi] = 0.3;
    EkfInput u;
    u << 0, 0, 0, 0, 0, -9.81;  // thrust along -z_b with the magnitude of g
    const EkfState xd = ekf_process_derivative(x, u, params);
    CHECK(xd[kV] == Approx(9.81 * std::sin(0.3)));  // v_dot = g sin(phi) > 0 when right wing down
    CHECK(xd[kW] == Approx(9.81 * (std::cos(0.3) - 1.0)));
  }
  SECTION("biases are subtracted from the IMU readings") {
    EkfState x = EkfState::Zero();
    x[kBiasP] = 0.2;
    x[kBiasAz] = -0.5;
    EkfInput u;
    u << 0.2, 0, 0, 0, 0, -9.81 - 0.5;
    CHECK(ekf_process_derivative(x, u, params).norm() < 1e-12);
  }
  SECTION("Euler kinematics equal W(phi, theta) * corrected rates") {
    EkfState x = EkfState::Zero();
    x.head<3>() << 0.4, -0.3, 1.0;
    EkfInput u;
    u << 1.0, -0.5, 0.3, 0, 0, -9.81;
    const Eigen::Vector3d expected = euler_rate_matrix(0.4, -0.3) * u.head<3>();
    CHECK((ekf_process_derivative(x, u, params).head<3>() - expected).norm() < 1e-12);
  }
}

TEST_CASE("EKF covariance propagation equals Phi (P + dt/2 Qc0) Phi^T + dt/2 Qc1", "[ekf_model]") {
  std::mt19937_64 rng(15);
  EkfConfig config;  // thesis Q, default bias random walks
  AttitudeVelocityEkf ekf(config);
  const EkfState x = random_state(rng);
  Eigen::Matrix<double, 12, 12> A = Eigen::Matrix<double, 12, 12>::Random();
  const EkfCovariance P0 = A * A.transpose() * 1e-3 + EkfCovariance::Identity() * 1e-4;
  const EkfInput u0 = random_input(rng);
  const EkfInput u1 = u0 + 0.05 * random_input(rng);
  const std::int64_t dt_us = 1953;
  const double dt = dt_us * 1e-6;
  ekf.initialize(0, x, P0);
  REQUIRE(ekf.predict(0, u0));
  REQUIRE(ekf.predict(dt_us, u1));

  // Reference: full 12x12 matrices.
  const EkfModelParams params = config.model_params();
  EkfCovariance F0, F1;
  EkfState x1;
  const EkfCovariance Phi = ekf_discrete_jacobian(x, u0, u1, dt, params, &F0, &F1, &x1);
  Eigen::Matrix<double, 6, 1> S;
  S << config.gyro_noise_var_per_sample_rad2ps2, config.accel_noise_var_per_sample_m2ps4;
  S /= config.process_noise_reference_rate_hz;
  Eigen::Matrix<double, 12, 1> qb = Eigen::Matrix<double, 12, 1>::Zero();
  qb.tail<3>() = config.accel_bias_rw_mps2_per_sqrts.array().square();
  qb.segment<3>(6) = config.gyro_bias_rw_radps_per_sqrts.array().square();
  const EkfInputJacobian G0 = ekf_input_jacobian(x, u0, params);
  const EkfInputJacobian G1 = ekf_input_jacobian(x1, u1, params);
  const EkfCovariance Qc0 = G0 * S.asDiagonal() * G0.transpose() + EkfCovariance(qb.asDiagonal());
  const EkfCovariance Qc1 = G1 * S.asDiagonal() * G1.transpose() + EkfCovariance(qb.asDiagonal());
  const EkfCovariance expected = Phi * (P0 + 0.5 * dt * Qc0) * Phi.transpose() + 0.5 * dt * Qc1;
  CHECK((ekf.covariance() - expected).cwiseAbs().maxCoeff() < 1e-12 * std::max(1.0, expected.cwiseAbs().maxCoeff()));
  EkfState x_expected = ekf_discrete_step(x, u0, u1, dt, params);
  ekf_wrap_angles(&x_expected);
  CHECK((ekf.state() - x_expected).norm() < 1e-12);
}
