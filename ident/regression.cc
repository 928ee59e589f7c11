#include "ident/regression.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>

namespace nimble::ident {
namespace {

/// Regressor matrix and dependent vector of one equation.
struct Design {
  Eigen::MatrixXd X;
  Eigen::VectorXd y;
};

const Eigen::VectorXd& signal(const SignalTable& signals, const std::string& name, const Equation& eq) {
  const auto it = signals.find(name);
  if (it == signals.end()) {
    throw std::invalid_argument("equation " + eq.name + ": no signal '" + name + "'");
  }
  return it->second;
}

std::vector<Design> build_designs(const SignalTable& signals, const std::vector<Equation>& equations) {
  if (equations.empty()) throw std::invalid_argument("regression: no equation");
  std::set<std::string> names;
  Eigen::Index n = -1;
  std::vector<Design> designs;
  for (const auto& eq : equations) {
    if (eq.regressors.empty()) throw std::invalid_argument("equation " + eq.name + " has no regressor");
    if (eq.parameters.size() != eq.regressors.size()) {
      throw std::invalid_argument("equation " + eq.name + ": " + std::to_string(eq.parameters.size()) +
                                  " parameter names for " + std::to_string(eq.regressors.size()) + " regressors");
    }
    if (!(eq.scale != 0.0) || !std::isfinite(eq.scale)) {
      throw std::invalid_argument("equation " + eq.name + ": scale must be finite and non-zero");
    }
    for (const auto& p : eq.parameters) {
      if (!names.insert(p).second) throw std::invalid_argument("parameter '" + p + "' appears twice");
    }
    const Eigen::VectorXd& y = signal(signals, eq.dependent, eq);
    if (n < 0) n = y.size();
    Design d;
    d.X.resize(n, static_cast<Eigen::Index>(eq.regressors.size()));
    for (std::size_t j = 0; j < eq.regressors.size(); ++j) {
      const Eigen::VectorXd& x = signal(signals, eq.regressors[j], eq);
      if (x.size() != n || y.size() != n) {
        throw std::invalid_argument("equation " + eq.name + ": signal '" + eq.regressors[j] + "' has " +
                                    std::to_string(x.size()) + " samples, '" + eq.dependent + "' has " +
                                    std::to_string(y.size()) + " and the first equation " + std::to_string(n));
      }
      d.X.col(static_cast<Eigen::Index>(j)) = x;
    }
    d.y = eq.scale * y;
    if (n <= d.X.cols()) {
      throw std::invalid_argument("equation " + eq.name + ": " + std::to_string(n) + " samples for " +
                                  std::to_string(d.X.cols()) + " parameters");
    }
    designs.push_back(std::move(d));
  }
  return designs;
}

/// (X'X)^-1 and theta of one equation by column-pivoting QR of the column-normalised X.
struct QrSolution {
  Eigen::VectorXd theta;
  Eigen::MatrixXd xtx_inv;
};

QrSolution solve_qr(const Design& d, const Equation& eq) {
  const Eigen::Index p = d.X.cols();
  Eigen::VectorXd norms = d.X.colwise().norm().transpose();
  for (Eigen::Index j = 0; j < p; ++j) {
    if (!(norms[j] > 0.0)) {
      throw std::invalid_argument("equation " + eq.name + ": regressor '" + eq.regressors[static_cast<std::size_t>(j)] +
                                  "' is zero throughout: the data does not excite it");
    }
  }
  const Eigen::MatrixXd Xn = d.X * norms.cwiseInverse().asDiagonal();
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(Xn);
  qr.setThreshold(1e-10);
  if (qr.rank() < p) {
    const Eigen::Index j = qr.colsPermutation().indices()[qr.rank()];
    throw std::invalid_argument("equation " + eq.name + ": regressor '" + eq.regressors[static_cast<std::size_t>(j)] +
                                "' is (nearly) a linear combination of the others: the parameters cannot be separated");
  }
  QrSolution s;
  s.theta = qr.solve(d.y).cwiseQuotient(norms);
  const Eigen::MatrixXd R = qr.matrixR().topLeftCorner(p, p).template triangularView<Eigen::Upper>();
  const Eigen::MatrixXd Rinv = R.template triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(p, p));
  const Eigen::MatrixXd perm = qr.colsPermutation();
  const Eigen::MatrixXd inv_n = perm * Rinv * Rinv.transpose() * perm.transpose();  // (Xn'Xn)^-1
  s.xtx_inv = norms.cwiseInverse().asDiagonal() * inv_n * norms.cwiseInverse().asDiagonal();
  return s;
}

/// Bartlett-weighted long-run covariance of the score rows G (N x P):
/// sum_{|k| <= K} (1 - |k| / (K + 1)) sum_i g_i g_{i+k}', computed as
/// (1 / (K + 1)) sum_j S_j S_j' over the sums S_j of every window of K + 1
/// consecutive rows (windows clipped at the ends), which counts each pair of
/// rows k apart exactly K + 1 - k times: O(N P^2) instead of O(N K P^2).
Eigen::MatrixXd long_run_covariance(const Eigen::MatrixXd& G, Eigen::Index lags) {
  const Eigen::Index n = G.rows(), p = G.cols();
  if (lags <= 0) return G.transpose() * G;
  Eigen::MatrixXd omega = Eigen::MatrixXd::Zero(p, p);
  Eigen::VectorXd window = Eigen::VectorXd::Zero(p);  // S_j, rows [j, j + K] clipped to [0, n)
  for (Eigen::Index j = -lags; j < n; ++j) {
    if (j + lags < n) window += G.row(j + lags).transpose();
    if (j - 1 >= 0) window -= G.row(j - 1).transpose();
    omega.selfadjointView<Eigen::Lower>().rankUpdate(window);
  }
  omega = omega.selfadjointView<Eigen::Lower>();
  return omega / static_cast<double>(lags + 1);
}

/// Fills the per-equation parts of `result` from the stacked theta and covariances.
void finish(RegressionResult& result, const std::vector<Equation>& equations, const std::vector<Design>& designs,
            const Eigen::VectorXd& theta, const Eigen::MatrixXd& cov, const Eigen::MatrixXd& cov_coloured) {
  result.covariance = cov;
  result.covariance_coloured = cov_coloured;
  result.parameter_names.clear();
  result.equations.clear();
  Eigen::Index offset = 0;
  for (std::size_t e = 0; e < equations.size(); ++e) {
    const Design& d = designs[e];
    const Eigen::Index p = d.X.cols();
    EquationResult r;
    r.equation = equations[e];
    r.theta = theta.segment(offset, p);
    r.covariance = cov.block(offset, offset, p, p);
    r.sigma = r.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
    r.sigma_coloured = cov_coloured.block(offset, offset, p, p).diagonal().cwiseMax(0.0).cwiseSqrt();
    r.correlation = correlation_of(r.covariance);
    r.y = d.y;
    r.fitted = d.X * r.theta;
    r.residual = d.y - r.fitted;
    r.residual_variance = r.residual.squaredNorm() / static_cast<double>(d.X.rows() - p);
    for (const auto& name : equations[e].parameters) result.parameter_names.push_back(name);
    result.equations.push_back(std::move(r));
    offset += p;
  }
}

Eigen::Index total_parameters(const std::vector<Design>& designs) {
  Eigen::Index p = 0;
  for (const auto& d : designs) p += d.X.cols();
  return p;
}

/// Inverse of a small symmetric positive definite matrix into `out` (column-major);
/// closed forms up to 3 x 3 (no allocation in the per-sample loop), LDLT beyond.
void invert_small_spd(const Eigen::MatrixXd& S, double* out) {
  const Eigen::Index n = S.rows();
  if (n == 1) {
    out[0] = 1.0 / S(0, 0);
  } else if (n == 2) {
    Eigen::Map<Eigen::Matrix2d> m(out);
    m = Eigen::Matrix2d(S).inverse();
  } else if (n == 3) {
    Eigen::Map<Eigen::Matrix3d> m(out);
    m = Eigen::Matrix3d(S).inverse();
  } else {
    Eigen::Map<Eigen::MatrixXd> m(out, n, n);
    m = S.ldlt().solve(Eigen::MatrixXd::Identity(n, n));
  }
}

/// GLS with flattened weights: column i of `w` holds W_i column-major (n_eq^2 rows).
RegressionResult gls(const std::vector<Equation>& equations, const std::vector<Design>& designs,
                     const Eigen::MatrixXd& w, const CovarianceOptions& copt) {
  const Eigen::Index ne = static_cast<Eigen::Index>(designs.size());
  const Eigen::Index n = designs.front().X.rows();
  const Eigen::Index P = total_parameters(designs);
  std::vector<Eigen::Index> offset(designs.size() + 1, 0);
  for (std::size_t e = 0; e < designs.size(); ++e) offset[e + 1] = offset[e] + designs[e].X.cols();

  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(P, P);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(P);
  for (Eigen::Index e = 0; e < ne; ++e) {
    const auto& Xe = designs[static_cast<std::size_t>(e)].X;
    Eigen::VectorXd wy = Eigen::VectorXd::Zero(n);
    for (Eigen::Index f = 0; f < ne; ++f) {
      const Eigen::VectorXd wef = w.row(e + f * ne).transpose();
      wy += wef.cwiseProduct(designs[static_cast<std::size_t>(f)].y);
      if (f < e) continue;
      const auto& Xf = designs[static_cast<std::size_t>(f)].X;
      const Eigen::MatrixXd block = Xe.transpose() * (wef.asDiagonal() * Xf);
      M.block(offset[static_cast<std::size_t>(e)], offset[static_cast<std::size_t>(f)], Xe.cols(), Xf.cols()) = block;
      M.block(offset[static_cast<std::size_t>(f)], offset[static_cast<std::size_t>(e)], Xf.cols(), Xe.cols()) =
          block.transpose();
    }
    b.segment(offset[static_cast<std::size_t>(e)], Xe.cols()) = Xe.transpose() * wy;
  }
  // Scale to unit diagonal before factorising: the parameters differ by orders of magnitude.
  const Eigen::VectorXd dscale = M.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd Ms = dscale.asDiagonal() * M * dscale.asDiagonal();
  Eigen::LDLT<Eigen::MatrixXd> ldlt(Ms);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() ||
      ldlt.vectorD().minCoeff() <= 1e-12 * ldlt.vectorD().maxCoeff()) {
    throw std::invalid_argument(
        "weighted least squares: the weighted normal equations are singular "
        "(regressors linearly dependent or weights degenerate)");
  }
  const Eigen::VectorXd theta = dscale.asDiagonal() * ldlt.solve(dscale.asDiagonal() * b);
  const Eigen::MatrixXd Minv = dscale.asDiagonal() * ldlt.solve(Eigen::MatrixXd::Identity(P, P)) * dscale.asDiagonal();

  // s^2 = sum_i r_i' W_i r_i / (N n_eq - P)
  Eigen::MatrixXd r(n, ne);
  for (Eigen::Index e = 0; e < ne; ++e) {
    const Design& d = designs[static_cast<std::size_t>(e)];
    r.col(e) = d.y - d.X * theta.segment(offset[static_cast<std::size_t>(e)], d.X.cols());
  }
  double chi2 = 0.0;
  for (Eigen::Index e = 0; e < ne; ++e) {
    for (Eigen::Index f = 0; f < ne; ++f) {
      chi2 += (w.row(e + f * ne).transpose().cwiseProduct(r.col(e)).cwiseProduct(r.col(f))).sum();
    }
  }
  const double s2 = chi2 / static_cast<double>(n * ne - P);

  // Scores g_i = X_i' W_i r_i.
  Eigen::MatrixXd G(n, P);
  for (Eigen::Index e = 0; e < ne; ++e) {
    Eigen::VectorXd wr = Eigen::VectorXd::Zero(n);
    for (Eigen::Index f = 0; f < ne; ++f) wr += w.row(e + f * ne).transpose().cwiseProduct(r.col(f));
    const Design& d = designs[static_cast<std::size_t>(e)];
    G.middleCols(offset[static_cast<std::size_t>(e)], d.X.cols()) = d.X.array().colwise() * wr.array();
  }
  const double dof = static_cast<double>(n * ne) / static_cast<double>(n * ne - P);
  const Eigen::MatrixXd coloured = dof * Minv * long_run_covariance(G, copt.correlation_lags) * Minv;

  RegressionResult result;
  result.method = Method::kWls;
  result.scale_factor = s2;
  finish(result, equations, designs, theta, s2 * Minv, coloured);
  return result;
}

RegressionResult ols(const std::vector<Equation>& equations, const std::vector<Design>& designs,
                     const CovarianceOptions& copt) {
  const Eigen::Index P = total_parameters(designs);
  const Eigen::Index n = designs.front().X.rows();
  std::vector<QrSolution> sol;
  Eigen::VectorXd theta(P);
  Eigen::MatrixXd resid(n, static_cast<Eigen::Index>(designs.size()));
  std::vector<Eigen::Index> offset;
  Eigen::Index off = 0;
  for (std::size_t e = 0; e < designs.size(); ++e) {
    sol.push_back(solve_qr(designs[e], equations[e]));
    theta.segment(off, designs[e].X.cols()) = sol.back().theta;
    resid.col(static_cast<Eigen::Index>(e)) = designs[e].y - designs[e].X * sol.back().theta;
    offset.push_back(off);
    off += designs[e].X.cols();
  }
  // Cov(theta_e, theta_f) = s_ef (Xe'Xe)^-1 Xe'Xf (Xf'Xf)^-1, s_ef = re'rf / sqrt((N - pe)(N - pf)).
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(P, P);
  double pooled = 0.0;
  for (std::size_t e = 0; e < designs.size(); ++e) {
    const Eigen::Index pe = designs[e].X.cols();
    for (std::size_t f = e; f < designs.size(); ++f) {
      const Eigen::Index pf = designs[f].X.cols();
      const double s_ef = resid.col(static_cast<Eigen::Index>(e)).dot(resid.col(static_cast<Eigen::Index>(f))) /
                          std::sqrt(static_cast<double>((n - pe) * (n - pf)));
      Eigen::MatrixXd block;
      if (e == f) {
        block = s_ef * sol[e].xtx_inv;
        pooled += s_ef;
      } else {
        block = s_ef * sol[e].xtx_inv * (designs[e].X.transpose() * designs[f].X) * sol[f].xtx_inv;
      }
      cov.block(offset[e], offset[f], pe, pf) = block;
      cov.block(offset[f], offset[e], pf, pe) = block.transpose();
    }
  }
  // Scores g_i = x_i r_i per equation; bread = blockdiag((Xe'Xe)^-1).
  Eigen::MatrixXd G(n, P);
  Eigen::MatrixXd bread = Eigen::MatrixXd::Zero(P, P);
  for (std::size_t e = 0; e < designs.size(); ++e) {
    const Eigen::Index pe = designs[e].X.cols();
    G.middleCols(offset[e], pe) = designs[e].X.array().colwise() * resid.col(static_cast<Eigen::Index>(e)).array();
    bread.block(offset[e], offset[e], pe, pe) = sol[e].xtx_inv;
  }
  const Eigen::Index nn = n * static_cast<Eigen::Index>(designs.size());
  const double dof = static_cast<double>(nn) / static_cast<double>(nn - P);
  const Eigen::MatrixXd coloured = dof * bread * long_run_covariance(G, copt.correlation_lags) * bread;

  RegressionResult result;
  result.method = Method::kOls;
  result.scale_factor = pooled / static_cast<double>(designs.size());
  finish(result, equations, designs, theta, cov, coloured);
  return result;
}

}  // namespace

Eigen::MatrixXd correlation_of(const Eigen::MatrixXd& cov) {
  const Eigen::VectorXd s = cov.diagonal().cwiseMax(0.0).cwiseSqrt();
  Eigen::MatrixXd c = cov;
  for (Eigen::Index i = 0; i < c.rows(); ++i) {
    for (Eigen::Index j = 0; j < c.cols(); ++j) {
      c(i, j) = (s[i] > 0.0 && s[j] > 0.0) ? cov(i, j) / (s[i] * s[j]) : (i == j ? 1.0 : 0.0);
    }
  }
  return c;
}

std::string to_string(Method m) {
  switch (m) {
    case Method::kOls: return "ols";
    case Method::kWls: return "wls";
    case Method::kOutputError: return "output-error";
  }
  return "?";
}

Method method_from_string(const std::string& name) {
  if (name == "ols") return Method::kOls;
  if (name == "wls") return Method::kWls;
  if (name == "output-error") return Method::kOutputError;
  throw std::invalid_argument("unknown method '" + name + "' (ols, wls or output-error)");
}

std::map<std::string, ParameterEstimate> RegressionResult::parameters() const {
  std::map<std::string, ParameterEstimate> out;
  for (const auto& eq : equations) {
    for (std::size_t j = 0; j < eq.equation.parameters.size(); ++j) {
      const Eigen::Index k = static_cast<Eigen::Index>(j);
      out[eq.equation.parameters[j]] = {eq.theta[k], eq.sigma[k], eq.sigma_coloured[k]};
    }
  }
  return out;
}

const EquationResult& RegressionResult::equation(const std::string& name) const {
  for (const auto& eq : equations) {
    if (eq.equation.name == name) return eq;
  }
  throw std::out_of_range("regression has no equation '" + name + "'");
}

std::vector<CorrelatedPair> correlated_pairs(const RegressionResult& result, double threshold) {
  std::vector<CorrelatedPair> out;
  for (const auto& eq : result.equations) {
    const Eigen::Index p = eq.correlation.rows();
    for (Eigen::Index i = 0; i < p; ++i) {
      for (Eigen::Index j = i + 1; j < p; ++j) {
        if (std::fabs(eq.correlation(i, j)) > threshold) {
          out.push_back({eq.equation.name, eq.equation.parameters[static_cast<std::size_t>(i)],
                         eq.equation.parameters[static_cast<std::size_t>(j)], eq.correlation(i, j)});
        }
      }
    }
  }
  return out;
}

RegressionResult estimate_ols(const SignalTable& signals, const std::vector<Equation>& equations,
                              const CovarianceOptions& covariance) {
  if (covariance.correlation_lags < 0) throw std::invalid_argument("correlation lags must be >= 0");
  return ols(equations, build_designs(signals, equations), covariance);
}

RegressionResult estimate_gls(const SignalTable& signals, const std::vector<Equation>& equations,
                              const std::vector<Eigen::MatrixXd>& weights, const CovarianceOptions& covariance) {
  if (covariance.correlation_lags < 0) throw std::invalid_argument("correlation lags must be >= 0");
  const std::vector<Design> designs = build_designs(signals, equations);
  const Eigen::Index ne = static_cast<Eigen::Index>(designs.size());
  const Eigen::Index n = designs.front().X.rows();
  if (static_cast<Eigen::Index>(weights.size()) != n) {
    throw std::invalid_argument("estimate_gls: " + std::to_string(weights.size()) + " weight matrices for " +
                                std::to_string(n) + " samples");
  }
  Eigen::MatrixXd w(ne * ne, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::MatrixXd& Wi = weights[static_cast<std::size_t>(i)];
    if (Wi.rows() != ne || Wi.cols() != ne) {
      throw std::invalid_argument("estimate_gls: weight matrix " + std::to_string(i) + " is not " + std::to_string(ne) +
                                  " x " + std::to_string(ne));
    }
    w.col(i) = Eigen::Map<const Eigen::VectorXd>(Wi.data(), ne * ne);
  }
  return gls(equations, designs, w, covariance);
}

RegressionResult estimate_wls(const SignalTable& signals, const std::vector<Equation>& equations,
                              const WlsOptions& options, const CovarianceOptions& covariance) {
  if (!(options.regularisation >= 0.0)) throw std::invalid_argument("WLS regularisation must be >= 0");
  if (covariance.correlation_lags < 0) throw std::invalid_argument("correlation lags must be >= 0");
  const std::vector<Design> designs = build_designs(signals, equations);
  const RegressionResult first = ols(equations, designs, CovarianceOptions{});
  const Eigen::Index ne = static_cast<Eigen::Index>(designs.size());
  const Eigen::Index n = designs.front().X.rows();

  Eigen::MatrixXd e(n, ne);
  for (Eigen::Index k = 0; k < ne; ++k) e.col(k) = first.equations[static_cast<std::size_t>(k)].residual;
  const Eigen::MatrixXd global = e.transpose() * e / static_cast<double>(n);
  const Eigen::Index L = (options.variance_window <= 0 || options.variance_window >= n) ? n : options.variance_window;

  // Prefix sums of e_a e_b for the moving-window covariance.
  const Eigen::Index pairs = ne * ne;
  Eigen::MatrixXd prefix = Eigen::MatrixXd::Zero(pairs, n + 1);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index a = 0; a < ne; ++a) {
      for (Eigen::Index b = 0; b < ne; ++b) prefix(a + b * ne, i + 1) = prefix(a + b * ne, i) + e(i, a) * e(i, b);
    }
  }
  const Eigen::MatrixXd reg = options.regularisation * global.diagonal().asDiagonal();
  Eigen::MatrixXd w(pairs, n);
  Eigen::MatrixXd S(ne, ne);
  S.setZero();
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index lo = std::clamp<Eigen::Index>(i - L / 2, 0, n - L);
    const Eigen::Index hi = lo + L;
    for (Eigen::Index k = 0; k < pairs; ++k) S.data()[k] = (prefix(k, hi) - prefix(k, lo)) / static_cast<double>(L);
    if (!options.cross_equation) S = Eigen::MatrixXd(S.diagonal().asDiagonal());
    S += reg;
    invert_small_spd(S, w.col(i).data());
  }
  if (!w.allFinite()) {
    throw std::invalid_argument("weighted least squares: a residual covariance is singular (OLS residuals are zero)");
  }
  return gls(equations, designs, w, covariance);
}

RegressionResult estimate(const SignalTable& signals, const std::vector<Equation>& equations, Method method,
                          const WlsOptions& options, const CovarianceOptions& covariance) {
  // Output error starts from the equation error's WLS (identify() refines it).
  return method == Method::kOls ? estimate_ols(signals, equations, covariance)
                                : estimate_wls(signals, equations, options, covariance);
}

}  // namespace nimble::ident
