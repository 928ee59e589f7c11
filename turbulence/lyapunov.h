#pragma once
/// Exact stationary covariances of white-noise driven linear systems: the continuous and the
/// discrete Lyapunov equations, solved by the Kronecker (vectorised) form. The systems of the
/// practical have at most 10 states (a 100 x 100 linear system); beyond ~30 states a
/// Bartels-Stewart solver would be the better choice.
///
/// White-noise intensities follow spectral_density.h: R_ww(tau) = W delta(tau).

#include <Eigen/Dense>

#include "turbulence/linear_system.h"

namespace nimble::turbulence {

/// P with A P + P A' + Q = 0 (symmetrised).
/// @throws std::invalid_argument if A is not square, Q has another size, or A is not Hurwitz
///         (an eigenvalue with real part >= 0 has no stationary covariance); the message names it.
Eigen::MatrixXd solve_continuous_lyapunov(const Eigen::MatrixXd& A, const Eigen::MatrixXd& Q);

/// P with P = Phi P Phi' + Q (symmetrised).
/// @throws std::invalid_argument if Phi has an eigenvalue with |z| >= 1 or the sizes differ.
Eigen::MatrixXd solve_discrete_lyapunov(const Eigen::MatrixXd& Phi, const Eigen::MatrixXd& Q);

/// Stationary state covariance of `sys` driven by independent white noises of intensity
/// `intensity` (one per input, 0 = not driven): A P + P A' + B diag(W) B' = 0.
/// @throws std::invalid_argument as solve_continuous_lyapunov, or if `intensity` does not fit.
Eigen::MatrixXd stationary_covariance(const LinearSystem& sys, const Eigen::VectorXd& intensity);

/// Output variances diag(C P C') of the stationary outputs [output unit^2].
/// @throws std::invalid_argument if an output has feedthrough (D != 0) from a driven input:
///         white noise passed straight to an output has infinite variance.
Eigen::VectorXd output_variances(const LinearSystem& sys, const Eigen::VectorXd& intensity, const Eigen::MatrixXd& P);

}  // namespace nimble::turbulence
