/// Output-error identification of the lateral3 structure (ident/output_error.h).

#include "ident/output_error.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace nimble::ident {
namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

/// The linear model x_dot = A x + B u of the parameters, states (p, v, phi).
struct Linear {
  Eigen::Matrix3d A;
  MatrixXd B;                                      // 3 x inputs
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();  // constant accelerations of p and v
};

/// What the simulation needs of the record and the equations.
struct Problem {
  std::vector<std::string> inputs;      // in the L equation's regressor order
  std::vector<Index> L_index, Y_index;  // per regressor of each equation: 0 p, 1 v, 2 + input
  double sL = 1.0, sY = 1.0, w0 = 0.0, g_phi = 0.0, dt = 0.0;
  MatrixXd U;                                     // samples x inputs
  MatrixXd Y;                                     // samples x 3: measured p, v, phi
  std::vector<std::pair<Index, Index>> segments;  // [first, last)
  Index nL = 0;                                   // parameters of L (then those of Y)
};

/// 0 for p, 1 for v, 2 + its column for any other regressor: an input, or an extra regressor or
/// term, which enters as its recorded column (its states' errors stay in it).
Index regressor_index(const std::string& r, std::vector<std::string>& inputs) {
  if (r == "p") return 0;
  if (r == "v") return 1;
  auto it = std::find(inputs.begin(), inputs.end(), r);
  if (it == inputs.end()) it = inputs.insert(inputs.end(), r);
  return 2 + (it - inputs.begin());
}

Linear linear_of(const Problem& P, const VectorXd& theta) {
  Linear m;
  m.A.setZero();
  m.B = MatrixXd::Zero(3, static_cast<Index>(P.inputs.size()));
  const auto add = [&](Index row, Index reg, double value) {
    if (reg < 2) {
      m.A(row, reg) += value;
    } else {
      m.B(row, reg - 2) += value;
    }
  };
  for (std::size_t j = 0; j < P.L_index.size(); ++j) add(0, P.L_index[j], theta[static_cast<Index>(j)] / P.sL);
  for (std::size_t j = 0; j < P.Y_index.size(); ++j) add(1, P.Y_index[j], theta[P.nL + static_cast<Index>(j)] / P.sY);
  m.A(1, 0) += P.w0;
  m.A(1, 2) += P.g_phi;
  m.A(2, 0) = 1.0;
  m.bias = Eigen::Vector3d(theta[theta.size() - 2], theta[theta.size() - 1], 0.0);  // theta: derivatives, biases
  return m;
}

/// Segment `i`'s simulated states, from the state `x`, written into its rows of X (samples x 3).
void simulate_segment(const Problem& P, const Linear& m, std::size_t i, Eigen::Vector3d x, MatrixXd& X) {
  const auto [a, b] = P.segments[i];
  const double h = P.dt;
  X.row(a) = x.transpose();
  for (Index k = a; k + 1 < b; ++k) {
    const VectorXd u0 = P.U.row(k).transpose(), u1 = P.U.row(k + 1).transpose();
    const VectorXd um = 0.5 * (u0 + u1);
    const Eigen::Vector3d k1 = m.A * x + m.B * u0 + m.bias;
    const Eigen::Vector3d k2 = m.A * (x + 0.5 * h * k1) + m.B * um + m.bias;
    const Eigen::Vector3d k3 = m.A * (x + 0.5 * h * k2) + m.B * um + m.bias;
    const Eigen::Vector3d k4 = m.A * (x + h * k3) + m.B * u1 + m.bias;
    x += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    X.row(k + 1) = x.transpose();
  }
}

/// Weighted cost of the residuals E (samples x 3) with weights w (1 / variance per output).
double cost_of(const MatrixXd& E, const Eigen::Vector3d& w) {
  return 0.5 * (E.array().square().rowwise() * w.transpose().array()).sum();
}

Problem problem_of(const UniformData& d, const std::vector<Equation>& equations, const Trim& trim, double gravity_mps2,
                   const OutputErrorOptions& o) {
  if (equations.size() != 2 || equations[0].name != "L" || equations[1].name != "Y") {
    throw std::invalid_argument("output error: the lateral3 structure's equations L and Y only");
  }
  if (!(o.segment_s > 0.0)) throw std::invalid_argument("output error: the segment must be > 0 s");
  Problem P;
  for (const auto& r : equations[0].regressors) P.L_index.push_back(regressor_index(r, P.inputs));
  for (const auto& r : equations[1].regressors) P.Y_index.push_back(regressor_index(r, P.inputs));
  P.nL = static_cast<Index>(P.L_index.size());
  P.sL = equations[0].scale;
  P.sY = equations[1].scale;
  P.w0 = trim.w0_mps;
  P.g_phi = gravity_mps2 * std::cos(trim.theta0_rad) * std::cos(trim.phi0_rad);
  P.dt = 1.0 / d.rate_hz;
  const Index n = d.size();
  P.U.resize(n, static_cast<Index>(P.inputs.size()));
  for (std::size_t i = 0; i < P.inputs.size(); ++i) {
    if (!d.has(P.inputs[i]))
      throw std::invalid_argument("output error: the record has no signal '" + P.inputs[i] + "'");
    P.U.col(static_cast<Index>(i)) = d.at(P.inputs[i]);
  }
  P.Y.resize(n, 3);
  P.Y << d.at("p"), d.at("v"), d.at("phi");
  const Index len = std::max<Index>(2, static_cast<Index>(std::lround(o.segment_s * d.rate_hz)));
  if (n < len) {
    throw std::invalid_argument("output error: the record (" + std::to_string(n) + " samples) is shorter than one " +
                                "segment (" + std::to_string(len) + ")");
  }
  for (Index a = 0; a + len <= n; a += len) P.segments.push_back({a, a + len});
  return P;
}

/// The weighted information matrix S' W S and gradient S' W e of the residuals E (samples x 3),
/// S their sensitivities stacked output by output, W the outputs' weights w.
void information(const MatrixXd& S, const MatrixXd& E, const Eigen::Vector3d& w, MatrixXd& M, VectorXd& g) {
  const Index m = E.rows();
  VectorXd wv(E.size());
  for (Index j = 0; j < 3; ++j) wv.segment(j * m, m).setConstant(w[j]);
  M = S.transpose() * wv.asDiagonal() * S;
  g = S.transpose() * (wv.asDiagonal() * Eigen::Map<const VectorXd>(E.data(), E.size()));
}

/// Cramer-Rao bounds of the first `nd` parameters at the solution: the inverse information
/// (white residuals) and its sandwich with the scores s_i = sum over outputs of S_i' w nu_i in
/// batches of `block` samples, longer than the residuals' correlation (coloured residuals).
void bounds(const MatrixXd& S, const MatrixXd& E, const Eigen::Vector3d& w, Index nd, Index block,
            OutputErrorResult& res) {
  const Index q = S.cols(), m = E.rows();
  MatrixXd M;
  VectorXd g;
  information(S, E, w, M, g);
  const MatrixXd Minv = M.ldlt().solve(MatrixXd::Identity(q, q));
  res.covariance = Minv.topLeftCorner(nd, nd);
  MatrixXd G = MatrixXd::Zero(q, q);
  for (Index a = 0; a < m; a += block) {
    const Index len = std::min(block, m - a);
    VectorXd s = VectorXd::Zero(q);
    for (Index j = 0; j < 3; ++j) s += w[j] * S.middleRows(j * m + a, len).transpose() * E.col(j).segment(a, len);
    G += s * s.transpose();
  }
  res.covariance_coloured = (Minv * G * Minv).topLeftCorner(nd, nd);
}

}  // namespace

OutputErrorResult output_error(const UniformData& data, const std::vector<Equation>& equations, const Trim& trim,
                               double gravity_mps2, const std::map<std::string, double>& start,
                               const OutputErrorOptions& options) {
  const Problem P = problem_of(data, equations, trim, gravity_mps2, options);
  OutputErrorResult res;
  for (const auto& eq : equations) {
    for (const auto& name : eq.parameters) res.parameter_names.push_back(name);
  }
  const Index nd = static_cast<Index>(res.parameter_names.size());  // the derivatives
  const Index ns = static_cast<Index>(P.segments.size());
  // and the two constant accelerations (started at 0), and each segment's initial state (started
  // at the measured one): a measured state's error at a segment's start would otherwise run
  // through the whole segment, amplified by the unstable mode.
  const Index q = nd + 2 + 3 * ns;
  VectorXd theta = VectorXd::Zero(q);
  for (Index i = 0; i < ns; ++i)
    theta.segment(nd + 2 + 3 * i, 3) = P.Y.row(P.segments[static_cast<std::size_t>(i)].first).transpose();
  for (Index j = 0; j < nd; ++j) {
    const auto it = start.find(res.parameter_names[static_cast<std::size_t>(j)]);
    if (it == start.end()) {
      throw std::invalid_argument("output error: no start value of " +
                                  res.parameter_names[static_cast<std::size_t>(j)]);
    }
    theta[j] = it->second;
  }
  res.segments = static_cast<int>(P.segments.size());
  // The samples the segments cover enter the cost, segment after segment: segment i's are rows
  // [i len, (i + 1) len) of the residuals (every segment has the same length).
  const Index len = P.segments.front().second - P.segments.front().first;
  const Index first = P.segments.front().first;
  const auto residuals = [&](const VectorXd& th) {
    const Linear lin = linear_of(P, th.head(nd + 2));
    MatrixXd X(P.Y.rows(), 3);
    for (Index i = 0; i < ns; ++i)
      simulate_segment(P, lin, static_cast<std::size_t>(i), th.segment(nd + 2 + 3 * i, 3), X);
    return MatrixXd(P.Y.middleRows(first, ns * len) - X.middleRows(first, ns * len));
  };
  MatrixXd E = residuals(theta);
  const auto weights_of = [](const MatrixXd& R) {
    Eigen::Vector3d w;
    for (Index j = 0; j < 3; ++j) w[j] = 1.0 / std::max(1e-300, R.col(j).squaredNorm() / static_cast<double>(R.rows()));
    return w;
  };
  Eigen::Vector3d w = weights_of(E);
  res.cost_start = cost_of(E, w);
  double lambda = 1e-3;
  const auto sensitivities = [&](const VectorXd& th, const MatrixXd& E0) {
    // d(model output) / d theta = -(dE / d theta), by forward differences. A derivative or a
    // constant acceleration moves every segment; a segment's initial state moves that segment
    // only, so only it is simulated again.
    MatrixXd out = MatrixXd::Zero(E0.size(), q);
    const Index m = E0.rows();
    const Linear lin = linear_of(P, th.head(nd + 2));
    MatrixXd X(P.Y.rows(), 3);
    for (Index j = 0; j < q; ++j) {
      VectorXd tp = th;
      const double step = 1e-6 * std::max(std::fabs(th[j]), 1e-3 * th.head(nd).cwiseAbs().maxCoeff() + 1e-12);
      tp[j] += step;
      if (j < nd + 2) {
        const MatrixXd Ep = residuals(tp);
        out.col(j) = Eigen::Map<const VectorXd>((E0 - Ep).eval().data(), E0.size()) / step;
        continue;
      }
      const Index i = (j - nd - 2) / 3;
      simulate_segment(P, lin, static_cast<std::size_t>(i), tp.segment(nd + 2 + 3 * i, 3), X);
      const Index a = P.segments[static_cast<std::size_t>(i)].first;
      const MatrixXd Ep = P.Y.middleRows(a, len) - X.middleRows(a, len);
      for (Index o = 0; o < 3; ++o) {
        out.col(j).segment(o * m + i * len, len) = (E0.col(o).segment(i * len, len) - Ep.col(o)) / step;
      }
    }
    return out;
  };
  for (res.iterations = 0; res.iterations < options.max_iterations; ++res.iterations) {
    w = weights_of(E);
    const double c0 = cost_of(E, w);
    const MatrixXd S = sensitivities(theta, E);  // (rows x 3) stacked output by output, q columns
    MatrixXd M;
    VectorXd g;
    information(S, E, w, M, g);
    bool improved = false;
    for (int tries = 0; tries < 12 && !improved; ++tries) {
      MatrixXd Md = M;
      Md.diagonal() *= (1.0 + lambda);
      const VectorXd step = Md.ldlt().solve(g);
      const VectorXd trial = theta + step;
      const MatrixXd Et = residuals(trial);
      const double c1 = cost_of(Et, w);
      if (std::isfinite(c1) && c1 < c0) {
        theta = trial;
        E = Et;
        lambda = std::max(1e-9, lambda / 10.0);
        improved = true;
        if ((c0 - c1) / c0 < options.tolerance) res.converged = true;
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) res.converged = true;  // no step lowers the cost: a minimum at this precision
    if (res.converged) break;
  }
  w = weights_of(E);
  res.cost = cost_of(E, w);
  res.theta = theta.head(nd);
  res.bias_p = theta[nd];
  res.bias_v = theta[nd + 1];
  bounds(sensitivities(theta, E), E, w, nd, options.coloured_block > 0 ? options.coloured_block : 64, res);
  return res;
}

}  // namespace nimble::ident
