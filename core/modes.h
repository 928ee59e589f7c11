#pragma once
/// Modal analysis of a linear model: eigenvalues, mode characteristics and
/// non-dimensional eigenvectors (thesis Eqs 30-32, normalised on the attitude angle).

#include <complex>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "core/model.h"
#include "core/vehicle.h"

namespace nimble {

/// One dynamic mode: a real eigenvalue or a complex-conjugate pair.
struct Mode {
  std::complex<double> eigenvalue;  ///< for a pair, the member with positive imaginary part
  bool oscillatory = false;
  bool stable = false;  ///< real part < 0
  double natural_frequency_radps = 0.0;
  double damping_ratio = 0.0;  ///< -re/|lambda| (1 or -1 for real eigenvalues)
  double period_s = 0.0;       ///< 2 pi / im; 0 for aperiodic modes
  /// ln 2 / |re|: time to double amplitude (unstable) or to halve it (stable); infinite for re = 0.
  double time_to_double_or_half_s = 0.0;
  /// Eigenvector made non-dimensional (scale_divisors) and normalised so that
  /// the attitude angle (phi or theta) component is 1 at 0 deg.
  Eigen::VectorXcd eigenvector_nondim;
};

/// Divisors that make each state non-dimensional (thesis Eqs 30-32):
/// rates / f, velocities / (2 Phi f r2), angles / (2 pi), with f the mean
/// flapping frequency [rad/s], Phi the flapping amplitude [rad], r2 the
/// radius of the second moment of wing area [m].
Eigen::VectorXd nondim_divisors(const StateSpace& ss, const Vehicle& vehicle);

/// Eigenvalues sorted by real part, then by imaginary part descending.
std::vector<std::complex<double>> sorted_eigenvalues(const Eigen::MatrixXd& A);

/// Modes of xdot = A x, sorted by real part of their eigenvalue.
/// The reference state for normalisation is "phi" or "theta", whichever the model has.
std::vector<Mode> analyse_modes(const StateSpace& ss, const Vehicle& vehicle);

}  // namespace nimble
