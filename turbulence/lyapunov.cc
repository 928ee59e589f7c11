#include "turbulence/lyapunov.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace nimble::turbulence {
namespace {

void check_square(const char* who, const Eigen::MatrixXd& A, const Eigen::MatrixXd& Q) {
  if (A.rows() != A.cols() || Q.rows() != A.rows() || Q.cols() != A.cols()) {
    throw std::invalid_argument(std::string(who) + ": A must be square and Q of its size");
  }
}

std::string format(const std::complex<double>& z) {
  std::ostringstream out;
  out << z.real() << (z.imag() < 0 ? " - " : " + ") << std::abs(z.imag()) << "i";
  return out.str();
}

/// Solves the n^2 x n^2 system K vec(P) = -vec(Q) and symmetrises P.
Eigen::MatrixXd solve_vectorised(const Eigen::MatrixXd& K, const Eigen::MatrixXd& Q) {
  const Eigen::Index n = Q.rows();
  const Eigen::VectorXd q = Eigen::Map<const Eigen::VectorXd>(Q.data(), n * n);
  const Eigen::VectorXd p = K.partialPivLu().solve(-q);
  const Eigen::MatrixXd P = Eigen::Map<const Eigen::MatrixXd>(p.data(), n, n);
  return 0.5 * (P + P.transpose());
}

}  // namespace

Eigen::MatrixXd solve_continuous_lyapunov(const Eigen::MatrixXd& A, const Eigen::MatrixXd& Q) {
  check_square("solve_continuous_lyapunov", A, Q);
  for (const auto& z : eigenvalues(A)) {
    if (!(z.real() < 0.0)) {
      throw std::invalid_argument("solve_continuous_lyapunov: eigenvalue " + format(z) +
                                  " is not stable: the system has no stationary covariance");
    }
  }
  const Eigen::Index n = A.rows();
  const Eigen::MatrixXd I = Eigen::MatrixXd::Identity(n, n);
  // vec(A P + P A') = (I (x) A + A (x) I) vec(P), column-major vec.
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n * n, n * n);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < n; ++j) {
      K.block(i * n, j * n, n, n) = A(i, j) * I;  // A (x) I
    }
    K.block(i * n, i * n, n, n) += A;  // I (x) A
  }
  return solve_vectorised(K, Q);
}

Eigen::MatrixXd solve_discrete_lyapunov(const Eigen::MatrixXd& Phi, const Eigen::MatrixXd& Q) {
  check_square("solve_discrete_lyapunov", Phi, Q);
  for (const auto& z : eigenvalues(Phi)) {
    if (!(std::abs(z) < 1.0)) {
      throw std::invalid_argument("solve_discrete_lyapunov: eigenvalue " + format(z) +
                                  " is not inside the unit circle: no stationary covariance");
    }
  }
  const Eigen::Index n = Phi.rows();
  // vec(Phi P Phi') = (Phi (x) Phi) vec(P); (Phi (x) Phi - I) vec(P) = -vec(Q).
  Eigen::MatrixXd K(n * n, n * n);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < n; ++j) K.block(i * n, j * n, n, n) = Phi(i, j) * Phi;
  }
  K -= Eigen::MatrixXd::Identity(n * n, n * n);
  return solve_vectorised(K, Q);
}

Eigen::MatrixXd stationary_covariance(const LinearSystem& sys, const Eigen::VectorXd& intensity) {
  sys.validate();
  if (intensity.size() != sys.n_inputs() || (intensity.array() < 0.0).any()) {
    throw std::invalid_argument("stationary_covariance: need one non-negative intensity per input (" +
                                std::to_string(sys.n_inputs()) + "), got " + std::to_string(intensity.size()));
  }
  const Eigen::MatrixXd Q = sys.B * intensity.asDiagonal() * sys.B.transpose();
  return solve_continuous_lyapunov(sys.A, Q);
}

Eigen::VectorXd output_variances(const LinearSystem& sys, const Eigen::VectorXd& intensity, const Eigen::MatrixXd& P) {
  for (Eigen::Index i = 0; i < sys.n_outputs(); ++i) {
    for (Eigen::Index j = 0; j < sys.n_inputs(); ++j) {
      if (intensity[j] > 0.0 && sys.D(i, j) != 0.0) {
        const std::string out = sys.outputs.empty() ? std::to_string(i) : sys.outputs[static_cast<std::size_t>(i)];
        const std::string in = sys.inputs.empty() ? std::to_string(j) : sys.inputs[static_cast<std::size_t>(j)];
        throw std::invalid_argument("output_variances: output " + out + " has feedthrough from the white noise " + in +
                                    ": infinite variance");
      }
    }
  }
  return (sys.C * P * sys.C.transpose()).diagonal();
}

}  // namespace nimble::turbulence
