#include "turbulence/discretisation.h"

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include <unsupported/Eigen/MatrixFunctions>

#include "core/model.h"

namespace nimble::turbulence {

Eigen::MatrixXd van_loan_noise_covariance(const Eigen::MatrixXd& A, const Eigen::MatrixXd& G, const Eigen::MatrixXd& W,
                                          double dt_s) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) throw std::invalid_argument("van_loan_noise_covariance: dt must be > 0");
  const Eigen::Index n = A.rows();
  if (A.cols() != n || G.rows() != n || W.rows() != G.cols() || W.cols() != G.cols()) {
    throw std::invalid_argument("van_loan_noise_covariance: sizes of A, G, W do not fit");
  }
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(2 * n, 2 * n);
  M.topLeftCorner(n, n) = -A * dt_s;
  M.topRightCorner(n, n) = G * W * G.transpose() * dt_s;
  M.bottomRightCorner(n, n) = A.transpose() * dt_s;
  const Eigen::MatrixXd E = M.exp();
  const Eigen::MatrixXd Phi = E.bottomRightCorner(n, n).transpose();
  const Eigen::MatrixXd Q = Phi * E.topRightCorner(n, n);
  return 0.5 * (Q + Q.transpose());
}

DiscreteModel discretise(const LinearSystem& sys, const Eigen::VectorXd& intensity, double dt_s) {
  sys.validate();
  if (intensity.size() != sys.n_inputs() || (intensity.array() < 0.0).any()) {
    throw std::invalid_argument("discretise: need one non-negative intensity per input (" +
                                std::to_string(sys.n_inputs()) + ")");
  }
  nimble::StateSpace ss;
  ss.A = sys.A;
  ss.B = sys.B;
  const nimble::DiscreteStateSpace zoh = nimble::discretize_zoh(ss, dt_s);
  DiscreteModel out;
  out.Phi = zoh.Ad;
  out.Gamma = zoh.Bd;
  out.Qd = van_loan_noise_covariance(sys.A, sys.B, Eigen::MatrixXd(intensity.asDiagonal()), dt_s);
  out.noise_factor = psd_factor(out.Qd);
  out.dt_s = dt_s;
  return out;
}

Eigen::MatrixXd held_noise_covariance(const DiscreteModel& model, const Eigen::VectorXd& intensity) {
  if (intensity.size() != model.Gamma.cols()) throw std::invalid_argument("held_noise_covariance: intensity size");
  return model.Gamma * (intensity / model.dt_s).asDiagonal() * model.Gamma.transpose();
}

Eigen::MatrixXd psd_factor(const Eigen::MatrixXd& S) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (S + S.transpose()));
  const Eigen::VectorXd root = es.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  return es.eigenvectors() * root.asDiagonal();
}

Eigen::MatrixXd simulate_stationary(const DiscreteModel& model, const Eigen::MatrixXd& P0, std::size_t samples,
                                    std::uint64_t seed) {
  const Eigen::Index n = model.Phi.rows();
  if (P0.rows() != n || P0.cols() != n) throw std::invalid_argument("simulate_stationary: P0 does not fit Phi");
  if (samples == 0) throw std::invalid_argument("simulate_stationary: no samples");
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::VectorXd e(n);
  const auto draw = [&]() {
    for (Eigen::Index i = 0; i < n; ++i) e[i] = normal(rng);
  };
  Eigen::MatrixXd X(static_cast<Eigen::Index>(samples), n);
  draw();
  Eigen::VectorXd x = psd_factor(P0) * e;
  X.row(0) = x.transpose();
  for (Eigen::Index k = 1; k < X.rows(); ++k) {
    draw();
    x = model.Phi * x + model.noise_factor * e;
    X.row(k) = x.transpose();
  }
  return X;
}

}  // namespace nimble::turbulence
