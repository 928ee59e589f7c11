#pragma once
/// Exact discretisation of a linear system with deterministic and white-noise inputs, and
/// its seeded simulation.
///
/// Deterministic inputs: zero-order hold by the matrix exponential,
///   Phi = exp(A dt), Gamma = integral_0^dt exp(A s) ds B (core/model.h discretize_zoh).
/// White-noise inputs of intensity W (spectral_density.h: R_ww = W delta): the state at the
/// next sample gets the integrated noise integral_0^dt exp(A s) G w(t+dt-s) ds, zero mean
/// with covariance
///   Q_d = integral_0^dt exp(A s) G W G' exp(A' s) ds,
/// computed by Van Loan's method: with M = [[-A, G W G'], [0, A']] dt and E = exp(M),
/// Phi = E22' and Q_d = Phi E12. Sampled this way, x_k has exactly the joint distribution of
/// the continuous process at t = k dt: for any dt the discrete stationary covariance solves
/// P = Phi P Phi' + Q_d with the continuous P (no Euler or held-noise variance error).
///
/// For comparison, the practical's simulation (lsim of randn / sqrt(dt), held over each step)
/// has process noise Gamma diag(W / dt) Gamma': held_noise_covariance().

#include <cstddef>
#include <cstdint>

#include <Eigen/Dense>

#include "turbulence/linear_system.h"

namespace nimble::turbulence {

/// x_{k+1} = Phi x_k + Gamma u_k + e_k with e_k ~ N(0, Qd) independent of the past.
struct DiscreteModel {
  Eigen::MatrixXd Phi;           ///< exp(A dt)
  Eigen::MatrixXd Gamma;         ///< ZOH input matrix of every input (deterministic use)
  Eigen::MatrixXd Qd;            ///< exact process-noise covariance of the driven white-noise inputs
  Eigen::MatrixXd noise_factor;  ///< L with L L' = Qd (symmetric eigen factor; Qd may be singular)
  double dt_s = 0.0;
};

/// Van Loan: the exact process-noise covariance of x_dot = A x + G w, w of intensity W
/// (square, symmetric, positive semi-definite), over one step dt.
/// @throws std::invalid_argument if dt is not > 0 or the sizes do not fit.
Eigen::MatrixXd van_loan_noise_covariance(const Eigen::MatrixXd& A, const Eigen::MatrixXd& G, const Eigen::MatrixXd& W,
                                          double dt_s);

/// Exact discretisation of `sys` at step dt: ZOH for every input (Gamma) and the Van Loan
/// process noise of the inputs with intensity > 0 (`intensity`, one per input).
/// @throws std::invalid_argument if dt is not > 0 and finite or `intensity` does not fit.
DiscreteModel discretise(const LinearSystem& sys, const Eigen::VectorXd& intensity, double dt_s);

/// The process noise of the practical's simulation: white noise replaced by samples of
/// variance W/dt held over each step, Gamma diag(W/dt) Gamma'. Its stationary covariance
/// (solve_discrete_lyapunov) differs from the continuous one by O(dt).
Eigen::MatrixXd held_noise_covariance(const DiscreteModel& model, const Eigen::VectorXd& intensity);

/// L with L L' = S for a symmetric positive semi-definite S (eigenvalues below 0 set to 0).
Eigen::MatrixXd psd_factor(const Eigen::MatrixXd& S);

/// A stationary record of `samples` states: x_0 ~ N(0, P0) (P0 = the stationary covariance
/// makes the record stationary from its first sample), x_{k+1} = Phi x_k + L n_k with
/// n_k ~ N(0, I) from std::mt19937_64(seed) and std::normal_distribution (deterministic for a
/// seed with the one standard library the rig is built with). One row per sample.
/// @throws std::invalid_argument if P0 does not fit or samples is 0.
Eigen::MatrixXd simulate_stationary(const DiscreteModel& model, const Eigen::MatrixXd& P0, std::size_t samples,
                                    std::uint64_t seed);

}  // namespace nimble::turbulence
