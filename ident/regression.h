#pragma once
/// Equation-error parameter estimation by linear regression (thesis Section
/// 4.3, Eqs 18-28 and 4.28-4.32; Appendix C).
///
/// An Equation is a named dependent signal times a scale, and a list of named
/// regressor signals, one parameter each:
///     scale * y(t) = sum_j theta_j * x_j(t) + e(t).
/// The signals come from a SignalTable, so any signal can be added as a
/// regressor (e.g. "v_abs_v" = v |v|) and tested.
///
/// OLS (Eq 4.28) solves each equation on its own by column-pivoting QR of the
/// column-normalised regressor matrix; sigma^2 = RSS / (N - p),
/// Cov = sigma^2 (X'X)^-1; cross-equation covariances use the residual
/// cross-covariance.
///
/// WLS (Eqs 24-28, 4.29-4.32) weights every sample with the inverse of the
/// covariance of the OLS residuals at that sample. E{e e'} cannot be estimated
/// from one residual per sample, so the covariance at sample i is the mean of
/// e_k e_k' over a window of samples centred on i (e_k the vector of the OLS
/// residuals of all equations at sample k). With `cross_equation` the full
/// n_eq x n_eq matrix is used and the equations are solved together
/// (generalised least squares of the stacked system); without it only its
/// diagonal (each equation weighted by its own residual variance). Then
/// theta = (sum_i X_i' W_i X_i)^-1 sum_i X_i' W_i y_i with X_i the
/// block-diagonal regressor rows at sample i, solved by LDLT, and
/// Cov = s^2 (sum_i X_i' W_i X_i)^-1 with s^2 = sum_i r_i' W_i r_i / (N n_eq - P)
/// (1 when the weights are the true inverse covariances).
/// With a window spanning the whole record the weights are constant and,
/// for equations sharing their regressors, WLS gives the OLS estimates.
///
/// Both covariances above assume residuals that are white (uncorrelated from
/// sample to sample). Residuals of low-pass filtered data are not: at 512 Hz
/// with a 9 Hz cut-off they are correlated over about rate / (2 cutoff) = 28
/// samples, and those standard deviations come out about sqrt(28) = 5 times
/// too small. Every result therefore also carries a covariance that holds
/// for coloured residuals (`covariance_coloured`, Newey-West): with the
/// scores g_i = X_i' W_i r_i (W_i = I for OLS) and the bread
/// B = (sum_i X_i' W_i X_i)^-1,
///     Cov = B [sum_{|k| <= K} (1 - |k| / (K + 1)) sum_i g_i g_{i+k}'] B * n / (n - P),
/// K = CovarianceOptions::correlation_lags, n = N n_eq. K = 0 gives the
/// heteroscedasticity-consistent (White) covariance.

#include <map>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "ident/signal.h"

namespace nimble::ident {

/// One regression equation: scale * dependent = sum_j parameters[j] * regressors[j] + e.
struct Equation {
  std::string name;                     ///< e.g. "L"; names the equation in tables and errors
  std::string dependent;                ///< signal name of the measured output, e.g. "p_dot"
  double scale = 1.0;                   ///< multiplies the dependent signal (e.g. Ic / Izz), != 0
  std::vector<std::string> regressors;  ///< signal names, e.g. {"p", "v", "delta_f", "delta_t"}
  std::vector<std::string> parameters;  ///< parameter names, one per regressor, unique over all equations
};

/// Estimation method.
/// kOutputError: the equation error's WLS for start values, then output error (ident/output_error.h).
enum class Method { kOls, kWls, kOutputError };

/// The correlation matrix of a covariance (1 on the diagonal; 0 beside a zero variance).
Eigen::MatrixXd correlation_of(const Eigen::MatrixXd& cov);

/// "ols", "wls" or "output-error".
std::string to_string(Method m);
/// @throws std::invalid_argument for another name.
Method method_from_string(const std::string& name);

/// Options of the WLS weights.
struct WlsOptions {
  /// Length of the window of the residual covariance [samples]; <= 0 or >= N:
  /// the whole record (constant weights).
  Eigen::Index variance_window = 256;
  /// Use the cross-equation residual covariance (generalised least squares of
  /// the stacked equations); false: only each equation's own variance.
  bool cross_equation = true;
  /// Added to each local covariance: regularisation * diag(global covariance), >= 0.
  double regularisation = 1e-3;
};

/// Options of the coloured-residual covariance.
struct CovarianceOptions {
  /// K: lags of the Bartlett window [samples], >= 0; cover the correlation
  /// time of the residuals (a few times rate / (2 cutoff) for filtered data).
  Eigen::Index correlation_lags = 0;
};

/// Estimate of one parameter.
struct ParameterEstimate {
  double value = 0.0;
  double sigma = 0.0;           ///< standard deviation assuming white residuals, in the unit of the value
  double sigma_coloured = 0.0;  ///< standard deviation allowing coloured residuals (Newey-West)
};

/// Result of one equation.
struct EquationResult {
  Equation equation;
  Eigen::VectorXd theta;           ///< parameters, in regressor order
  Eigen::VectorXd sigma;           ///< their standard deviations (white residuals)
  Eigen::VectorXd sigma_coloured;  ///< their standard deviations (coloured residuals)
  Eigen::MatrixXd covariance;      ///< of theta (white residuals)
  Eigen::MatrixXd correlation;     ///< of theta (1 on the diagonal)
  Eigen::VectorXd y;               ///< scale * dependent
  Eigen::VectorXd fitted;          ///< X theta
  Eigen::VectorXd residual;        ///< y - fitted
  double residual_variance = 0.0;  ///< residual' residual / (N - p)
};

/// Result of a regression over one or more equations.
struct RegressionResult {
  Method method = Method::kOls;
  std::vector<EquationResult> equations;
  std::vector<std::string> parameter_names;  ///< all parameters, equation by equation
  Eigen::MatrixXd covariance;                ///< of all parameters, same order (white residuals)
  Eigen::MatrixXd covariance_coloured;       ///< the same allowing coloured residuals
  /// s^2 of the weighted residuals (WLS; 1 for weights that are the true inverse
  /// covariances); the per-equation residual variance pooled for OLS.
  double scale_factor = 1.0;

  /// Value and sigma of every parameter, by name.
  std::map<std::string, ParameterEstimate> parameters() const;
  /// @throws std::out_of_range naming the equation if absent.
  const EquationResult& equation(const std::string& name) const;
};

/// A pair of parameters of one equation whose estimates are strongly correlated.
struct CorrelatedPair {
  std::string equation;
  std::string a, b;
  double rho = 0.0;
};

/// Pairs with |rho| > threshold inside each equation (thesis Appendix H:
/// critical value 0.9), in equation and parameter order.
std::vector<CorrelatedPair> correlated_pairs(const RegressionResult& result, double threshold = 0.9);

/// Ordinary least squares, each equation on its own.
/// @throws std::invalid_argument if a signal is missing or of another length,
///         an equation has no regressor, a parameter name repeats, there are
///         fewer samples than parameters, or the regressors of an equation are
///         linearly dependent (naming the regressor that adds no information).
RegressionResult estimate_ols(const SignalTable& signals, const std::vector<Equation>& equations,
                              const CovarianceOptions& covariance = {});

/// Weighted least squares with weights from the OLS residual covariance (see above).
/// @throws std::invalid_argument as estimate_ols, or for a negative regularisation.
RegressionResult estimate_wls(const SignalTable& signals, const std::vector<Equation>& equations,
                              const WlsOptions& options, const CovarianceOptions& covariance = {});

/// Generalised least squares with given weights: weights[i] is the
/// n_eq x n_eq inverse covariance of the equation residuals at sample i
/// (symmetric, positive definite). The building block of estimate_wls.
/// @throws std::invalid_argument as estimate_ols, or if weights has the wrong size.
RegressionResult estimate_gls(const SignalTable& signals, const std::vector<Equation>& equations,
                              const std::vector<Eigen::MatrixXd>& weights, const CovarianceOptions& covariance = {});

/// OLS or WLS by `method`.
RegressionResult estimate(const SignalTable& signals, const std::vector<Equation>& equations, Method method,
                          const WlsOptions& options, const CovarianceOptions& covariance = {});

}  // namespace nimble::ident
