#pragma once
/// Output-error identification of the lateral3 structure (Klein & Morelli, Aircraft System
/// Identification, ch. 6; SIDPAC `oe`): the model's states simulated from the recorded inputs and
/// fitted to the measured states by Gauss-Newton with Levenberg-Marquardt damping, instead of the
/// equation error's regression of differentiated states on measured ones.
///
/// Why: the equation error's regressors are the measured (smoothed) states. Their errors, and
/// the derivative's window over process noise the closed loop's states have already answered,
/// bias it (Yv by -3 to -9 % from smoothed states on sets 2-5 of the thesis's campaign). In
/// output error the regressors are the model's own simulated states, free of those errors.
///
/// The Nimble is unstable without its controller, so one simulation of a whole closed-loop record
/// from its recorded flap input diverges. The record is cut into segments (`segment_s`), each
/// simulated from the measured state at its start (multiple shooting): the measured state enters
/// once per segment, not at every sample.
///
/// Model (lateral_equations(), the regressors p, v and the inputs; an extra regressor or a term
/// enters as its recorded column, as an input does, so its states' errors stay in it):
///   p_dot   = (1 / sL) (Lp p + Lv v + sum_u L_u u)
///   v_dot   = (1 / sY) (Yp p + Yv v + sum_u Y_u u) + w0 p + g cos(theta0) cos(phi0) phi
///   phi_dot = p
/// plus a constant acceleration in each of p_dot and v_dot (OutputErrorResult::bias_p, bias_v),
/// integrated by fourth-order Runge-Kutta at the data's sample time, the inputs linear between
/// samples. Outputs: p, v, phi, weighted by the inverse of their residual variances (updated each
/// iteration, Klein & Morelli Eq 6.4). Cramer-Rao bounds: the inverse information matrix (white
/// residuals) and, allowing coloured residuals, its sandwich with the scores' batch means
/// (Morelli & Klein 1997), blocks of `coloured_block` samples. On six-second closed-loop
/// flights from smoothed states even the coloured bound is 1.1 to 2.6 times below the estimates'
/// spread over seeds (docs/paper-flights.md): a lower bound.

#include <map>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "core/model.h"
#include "ident/regression.h"
#include "ident/signal.h"

namespace nimble::ident {

struct OutputErrorOptions {
  double segment_s = 2.0;  ///< multiple-shooting segment [s], > 0
  int max_iterations = 40;
  double tolerance = 1e-9;  ///< relative fall of the cost below which the fit has converged
  Eigen::Index coloured_block =
      0;  ///< batch length of the coloured bounds [samples]; 0: 64 (rig identify: 4 x its coloured lags)
};

struct OutputErrorResult {
  std::vector<std::string> parameter_names;  ///< equation by equation, in regressor order
  Eigen::VectorXd theta;
  /// Constant accelerations of p [rad/s^2] and v [m/s^2] fitted beside the derivatives: the
  /// measured states' offsets (a tilt of the attitude reference drives v through g phi), which a
  /// simulation integrates and the derivatives would otherwise absorb.
  double bias_p = 0.0, bias_v = 0.0;
  Eigen::MatrixXd covariance;           ///< Cramer-Rao, white residuals
  Eigen::MatrixXd covariance_coloured;  ///< allowing coloured residuals
  int iterations = 0;
  bool converged = false;
  double cost_start = 0.0, cost = 0.0;  ///< weighted output error at the start values and at the end
  int segments = 0;
};

/// Output error on `data` (filtered, with p, v, phi and every input of `equations`), from the
/// start values `start` (the equation error's). `equations`: lateral_equations() of lateral3.
/// @throws std::invalid_argument for another structure's equations, a missing signal, or a record
///         shorter than one segment.
OutputErrorResult output_error(const UniformData& data, const std::vector<Equation>& equations, const Trim& trim,
                               double gravity_mps2, const std::map<std::string, double>& start,
                               const OutputErrorOptions& options);

}  // namespace nimble::ident
