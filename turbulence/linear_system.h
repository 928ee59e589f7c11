#pragma once
/// A continuous linear time-invariant system x_dot = A x + B u, y = C x + D u with named
/// states, inputs and outputs: the common currency of the turbulence library (shaping
/// filters, the Ce500 model, its closed loop and its reduced form).

#include <complex>
#include <string>
#include <vector>

#include <Eigen/Dense>

namespace nimble::turbulence {

/// x_dot = A x + B u, y = C x + D u. Time in s, frequencies in rad/s.
struct LinearSystem {
  Eigen::MatrixXd A;                 ///< n x n
  Eigen::MatrixXd B;                 ///< n x m
  Eigen::MatrixXd C;                 ///< p x n
  Eigen::MatrixXd D;                 ///< p x m
  std::vector<std::string> states;   ///< n names (with units where useful)
  std::vector<std::string> inputs;   ///< m names
  std::vector<std::string> outputs;  ///< p names

  Eigen::Index n_states() const { return A.rows(); }
  Eigen::Index n_inputs() const { return B.cols(); }
  Eigen::Index n_outputs() const { return C.rows(); }

  /// @throws std::invalid_argument naming the matrix whose size does not fit, or a
  ///         name list whose length differs from its dimension (an empty list is allowed).
  void validate() const;
};

/// Index of `name` in `names`. @throws std::invalid_argument listing the names if absent.
Eigen::Index index_of(const std::vector<std::string>& names, const std::string& name);

/// H(i omega) = C (i omega I - A)^-1 B + D, p x m.
/// @throws std::invalid_argument if i omega is an eigenvalue of A (singular resolvent).
Eigen::MatrixXcd frequency_response(const LinearSystem& sys, double omega_radps);

/// The loop closed by the state feedback u_j = -K x on input `input` (the other inputs stay
/// open): A - B_j K, and C - D_j K for the outputs. The input keeps its column in B and D, so
/// that an additional command on it still enters.
/// @throws std::invalid_argument if K has not n_states columns or the input does not exist.
LinearSystem close_state_feedback(const LinearSystem& sys, const std::string& input, const Eigen::RowVectorXd& K);

/// Eigenvalues of A, sorted by real part descending, then by imaginary part descending.
std::vector<std::complex<double>> eigenvalues(const Eigen::MatrixXd& A);

}  // namespace nimble::turbulence
