#pragma once
/// Analytical power spectral densities of linear systems driven by white noise, and their
/// integral to a variance.
///
/// THE PSD CONVENTION OF THE WHOLE LIBRARY (the practical's, Eq 5.1):
///   S_xx(omega) = integral_{-inf}^{inf} R_xx(tau) exp(-i omega tau) d tau,
///   sigma_x^2   = R_xx(0) = (1/pi) integral_0^inf S_xx(omega) d omega,
/// with omega in rad/s and S in unit^2/(rad/s) (= unit^2 s). S is even in omega; it is the
/// two-sided density, and the one-sided integral carries 1/pi (not 1/(2 pi)). No estimate in
/// this library is doubled for one-sided use: doubling it and also integrating with 1/pi
/// counts the factor 2 twice (a known defect of public solutions of the practical).
///
/// White noise of intensity W has R_ww(tau) = W delta(tau), hence S_ww(omega) = W: "unit
/// intensity" (the practical's w1, w2, w3) is W = 1 and has S = 1 at every frequency. The
/// same W enters the Lyapunov equation A P + P A' + B W B' = 0 (lyapunov.h) and the exact
/// discrete process noise (discretisation.h). Held over a step dt, such a noise has sample
/// variance W / dt (the practical's randn / sqrt(dt)).
///
/// Independent inputs add in power: S_yy = sum_j |H_yj(i omega)|^2 W_j, never
/// (sum_j |H_yj| sqrt(W_j))^2 (the second defect; coherent_output_psd() computes it only to
/// show its size).
///
/// Conversion to the one-sided PSD in unit^2/Hz of ident/spectrum.h: G(f) = 2 S(2 pi f).

#include <functional>
#include <limits>

#include <Eigen/Dense>

#include "turbulence/linear_system.h"

namespace nimble::turbulence {

/// Output PSDs of `sys` at `omega_radps` driven by independent white noises of intensity
/// `intensity` (one entry per input, 0 for an input that is not driven):
/// S_i = sum_j |H_ij(i omega)|^2 W_j [output unit^2 / (rad/s)].
/// @throws std::invalid_argument if `intensity` has not one entry per input or a negative entry.
Eigen::VectorXd output_psd(const LinearSystem& sys, const Eigen::VectorXd& intensity, double omega_radps);

/// output_psd() on a grid: one row per frequency, one column per output.
Eigen::MatrixXd output_psd(const LinearSystem& sys, const Eigen::VectorXd& intensity,
                           const Eigen::VectorXd& omega_radps);

/// The defective sum (sum_j |H_ij| sqrt(W_j))^2 of independent inputs, for diagnosis only: it is
/// not the PSD of the output (it adds amplitudes of uncorrelated signals).
Eigen::VectorXd coherent_output_psd(const LinearSystem& sys, const Eigen::VectorXd& intensity, double omega_radps);

/// A numerical integral with its error estimate.
struct Quadrature {
  double value = 0.0;
  double error = 0.0;  ///< |I(2n) - I(n)|: the change from the last doubling of the panels
  int panels = 0;
};

/// integrate_psd() of several PSDs at once (one entry per component, e.g. per output); the
/// panels are doubled until every component has converged. error holds the largest change.
struct VectorQuadrature {
  Eigen::VectorXd value;
  Eigen::VectorXd error;
  int panels = 0;
};
VectorQuadrature integrate_psds(const std::function<Eigen::VectorXd(double)>& psds,
                                double omega_max_radps = std::numeric_limits<double>::infinity(),
                                double omega_scale_radps = 1.0, double rel_tol = 1e-10);

/// (1/pi) integral_0^omega_max S(omega) d omega: the variance of a PSD in this library's
/// convention. The substitution omega = omega_scale tan(theta) maps [0, inf) onto [0, pi/2);
/// composite 5-point Gauss-Legendre panels on theta (no end point is evaluated, so
/// omega_max = inf is fine for S falling at least like 1/omega^2), doubled from 64 panels
/// until the change is below rel_tol of the value (at most 2^16 panels).
/// @throws std::invalid_argument if omega_max or omega_scale is not > 0.
Quadrature integrate_psd(const std::function<double(double)>& psd,
                         double omega_max_radps = std::numeric_limits<double>::infinity(),
                         double omega_scale_radps = 1.0, double rel_tol = 1e-10);

/// Exact PSD of the sampled process y_k = C x(k dt) of a stationary discrete model
/// x_{k+1} = Phi x_k + noise with stationary covariance P, in this library's convention
/// (dt * the discrete-time Fourier transform of R_k = C Phi^|k| P C'), for 0 <= omega <= pi/dt:
///   S_d(omega) = dt (C P C' + 2 Re{C (z I - Phi)^-1 Phi P C'}),  z = exp(i omega dt).
/// It contains the aliasing the periodogram of a record sampled at dt sees; for dt -> 0 it
/// tends to the analytical output PSD. One row per frequency, one column per row of C.
Eigen::MatrixXd sampled_output_psd(const Eigen::MatrixXd& Phi, const Eigen::MatrixXd& P, const Eigen::MatrixXd& C,
                                   double dt_s, const Eigen::VectorXd& omega_radps);

}  // namespace nimble::turbulence
